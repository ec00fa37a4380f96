"""Adapters for reinforcement-learning libraries on top of the environment.

``sb3``: a Stable-Baselines3 ``VecEnv`` over many worlds (``GatheringVecEnv``).
``torchrl_env``: a batched TorchRL env over many worlds (``GatheringTorchEnv``, one group of N robots).
``benchmarl_task``: the BenchMARL tasks ``gathering/env1..3`` (``GatheringTask``);
``benchmarl_hydra``: BenchMARL's hydra command line with those tasks registered.
``seeds``: the episode-seed helpers they share. Each adapter imports its library, so this
package imports nothing on its own.
"""
