"""Adapters for reinforcement-learning libraries on top of the environment.

``sb3``: a Stable-Baselines3 ``VecEnv`` over many worlds (``GatheringVecEnv``). Each adapter
imports its library, so this package imports nothing on its own.
"""
