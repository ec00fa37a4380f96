"""W worlds as one batched TorchRL environment: one group of N robots, many worlds per call.

``GatheringTorchEnv(num_worlds=W, seed=0, environment=1, max_cycles=2000, reward="shaped")``
is a ``torchrl.envs.EnvBase`` of batch size ``[W]`` over ``VectorSimulation``: one step of
the env is one compiled step of all W worlds. Its keys are those TorchRL's
``PettingZooWrapper`` gives the PettingZoo env (one group, ``"robot"``), so a policy trained
on either runs on the other::

    ("robot", "observation")  (W, N, S) float32 in [0, 1]   the morphology's readings
    ("robot", "action")       (W, N, 2) float32 in [-1, 1]  left, right wheel
    ("robot", "reward")       (W, N, 1) float32             VectorSimulation.robot_rewards()
    "state"                   (W, D) float32                the global state (gathering_env.state)
    "done" / "terminated" / "truncated"  (W, 1) bool        the world's episode ended
    "task_performance"        (W,) float32                  ft of the episode so far (final when done)

Ended worlds are not stepped (``VectorSimulation`` masks them) until TorchRL resets them with a
``"_reset"`` mask (collectors do it after every step, ``rollout(break_when_any_done=False)``
too); each reset world draws a new episode seed from one generator seeded by ``seed`` /
``set_seed``, so runs are reproducible and world w's episode is exactly the PettingZoo env's
for the same episode seed.

Needs TorchRL (``pip install 'gathering-evolution[marl]'``); nothing else in the package imports it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from ..sensors import Morphology
from ..state import state_space
from ..vector import VectorSimulation
from .seeds import check_seed, episode_seeds

GROUP = "robot"
"""The agents' group: the name TorchRL's ``PettingZooWrapper`` gives ``robot_0 ... robot_{N-1}``."""


class GatheringTorchEnv(EnvBase):
    """W worlds of N robots, batch size ``[W]`` (see the module docstring).

    Args:
        num_worlds: W worlds stepped together.
        seed: seeds the generator of episode seeds (None: fresh entropy).
        morphology: every robot's sensor suite (default Khepera III).
        return_state: include ``"state"`` (the global state, for centralised critics).
        device: torch device of the tensors (the simulation runs on the CPU).
        **world_parameters: ``WorldConfig.from_kwargs`` arguments (``environment``,
            ``max_cycles``, ``reward``, ``reward_scope``, ...).
    """

    def __init__(self, num_worlds: int = 1, seed: int | None = None,
                 morphology: Morphology | Sequence | dict | None = None, return_state: bool = True,
                 device: Any = "cpu", **world_parameters: Any) -> None:
        self.sim = VectorSimulation(num_worlds, morphology=morphology, **world_parameters)
        self.config = self.sim.config
        self.num_worlds, self.num_robots = self.sim.num_worlds, self.config.num_robots
        self.return_state = bool(return_state)
        super().__init__(device=device, batch_size=torch.Size([self.num_worlds]))
        self._seed = check_seed(seed)
        self._rng = np.random.default_rng(self._seed)
        self._started = False
        self._make_specs()

    @property
    def group_map(self) -> dict[str, list[str]]:
        """``{"robot": ["robot_0", ..., "robot_{N-1}"]}``, as TorchRL's PettingZoo wrapper groups them."""
        return {GROUP: [f"robot_{i}" for i in range(self.num_robots)]}

    def _make_specs(self) -> None:
        w, n, s = self.num_worlds, self.num_robots, len(self.sim.morphology)
        group_obs = Composite(observation=Bounded(0.0, 1.0, (w, n, s), dtype=torch.float32, device=self.device),
                              shape=(w, n), device=self.device)
        observation = Composite({GROUP: group_obs}, shape=(w,), device=self.device)
        observation["task_performance"] = Unbounded((w,), dtype=torch.float32, device=self.device)
        if self.return_state:
            box = state_space(self.config)
            observation["state"] = Bounded(torch.as_tensor(np.tile(box.low, (w, 1))),
                                           torch.as_tensor(np.tile(box.high, (w, 1))), (w, box.shape[0]),
                                           dtype=torch.float32, device=self.device)
        self.observation_spec = observation
        self.action_spec = Composite(
            {GROUP: Composite(action=Bounded(-1.0, 1.0, (w, n, 2), dtype=torch.float32, device=self.device),
                              shape=(w, n), device=self.device)}, shape=(w,), device=self.device)
        self.reward_spec = Composite(
            {GROUP: Composite(reward=Unbounded((w, n, 1), dtype=torch.float32, device=self.device),
                              shape=(w, n), device=self.device)}, shape=(w,), device=self.device)
        flag = Categorical(2, (w, 1), dtype=torch.bool, device=self.device)
        self.done_spec = Composite(done=flag.clone(), terminated=flag.clone(), truncated=flag.clone(),
                                   shape=(w,), device=self.device)

    # ------------------------------------------------------------------ EnvBase API
    def _set_seed(self, seed: int | None) -> None:
        self._seed = check_seed(seed)
        self._rng = np.random.default_rng(self._seed)

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        mask = None
        if tensordict is not None and "_reset" in tensordict.keys():
            mask = tensordict.get("_reset").reshape(self.num_worlds).cpu().numpy()
        if mask is None or not self._started:
            self.sim.reset(self._episode_seeds(self.num_worlds))
            self._started = True
        else:
            for w in np.flatnonzero(mask):
                self.sim.reset_world(int(w), self._episode_seeds(1)[0])
        ended, gathered_all = ~self.sim.active, self.sim.gathered().all(axis=1)
        return self._output(self.sim.observations(), None, ended & gathered_all, ended & ~gathered_all)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        wheels = tensordict.get((GROUP, "action")).detach().cpu().numpy().astype(np.float64)
        obs, _, terminated, truncated = self.sim.step(wheels)
        return self._output(obs, self.sim.robot_rewards(), terminated, truncated)

    # ------------------------------------------------------------------ helpers
    def _output(self, obs: np.ndarray, rewards: np.ndarray | None, terminated: np.ndarray,
                truncated: np.ndarray) -> TensorDictBase:
        w, device = self.num_worlds, self.device
        group = {"observation": torch.as_tensor(obs, dtype=torch.float32, device=device)}
        if rewards is not None:
            group["reward"] = torch.as_tensor(rewards, dtype=torch.float32, device=device).unsqueeze(-1)
        terminated_t = torch.as_tensor(terminated, device=device).reshape(w, 1)
        truncated_t = torch.as_tensor(truncated, device=device).reshape(w, 1)
        out = {GROUP: TensorDict(group, batch_size=(w, self.num_robots), device=device),
               "done": terminated_t | truncated_t, "terminated": terminated_t, "truncated": truncated_t,
               "task_performance": torch.as_tensor(self.sim.task_performance(), dtype=torch.float32, device=device)}
        if self.return_state:
            out["state"] = torch.as_tensor(self.sim.states(), device=device)
        return TensorDict(out, batch_size=(w,), device=device)

    def _episode_seeds(self, count: int) -> list[int]:
        return episode_seeds(self._rng, count)


__all__ = ["GROUP", "GatheringTorchEnv"]
