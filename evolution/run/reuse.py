"""Score each distinct team once: genomes that decode to the same team share its evaluation.

Breeding makes many genomes whose decoded team is exactly that of another genome: a mutation
of a disabled connection, of a CPPN part that no queried output depends on, or below a link
threshold changes the genome but not the controller or the sensors. Measured on the S1-original
run (HyperNEAT-M, 150 genomes): 73–76 distinct teams a generation. An evaluation depends on
nothing but the decoded team (controller and morphology) and its episodes' seeds, and the
simulation is deterministic, so such a genome takes the stored evaluation of its team instead
of a new simulation, with the same scores, and ``steps`` and timings 0 (no work was done for
it). The statistics are those of scoring every genome, ``steps`` aside (what was simulated).

A team is identified by the SHA-256 of its controller's and morphology's JSON form, which
holds every weight and sensor parameter exactly (floats by their shortest repr); with its
episodes' seeds (``episode_seeds``) that is the key. With ``layout = "per_run"`` every
generation has the same episode, so a team scored in any earlier generation is reused too;
with fresh layouts only teams of the same generation share. Failed evaluations are not stored.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from typing import Any

from evolution.run.evaluate import Evaluation, decode_genome, episode_seeds


def team_key(controller: Any, morphology: Any) -> str:
    """The identity of a decoded team: equal keys, equal behaviour in every episode."""
    text = json.dumps([controller.to_dict(), morphology.to_dict()], sort_keys=True, allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


class ReusingEvaluator:
    """An evaluator that simulates each distinct team once and hands its evaluation to every
    genome that decodes to it; ``inner`` (any backend, or ``evolution.run.rebuild``'s) does the work.

    ``reused`` / ``asked``: genomes that took a stored evaluation / that were asked for, so far.
    """

    def __init__(self, inner: Any, context: Any) -> None:
        self.inner = inner
        self.context = context
        self.name = inner.name
        self.failures = inner.failures
        self.reused = self.asked = 0
        self._store: dict[tuple[str, tuple[int, ...]], Evaluation] = {}

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        ctx = self.context
        seeds = tuple(episode_seeds(ctx.seed, generation, ctx.trials, ctx.layout, ctx.env_config))
        if any(k[1] != seeds for k in self._store):  # fresh layouts: last generation's teams never recur
            self._store = {k: v for k, v in self._store.items() if k[1] == seeds}
        keys = [(team_key(*decode_genome(ctx.method, g, ctx.neat_config, ctx.substrate)), seeds) for g in genomes]
        if self.rebuilds(generation):
            first = list(range(len(genomes)))  # a rebuilt generation: every genome answered from its record
        else:
            seen: set[Any] = set()
            first = []
            for i, key in enumerate(keys):
                if key not in self._store and key not in seen:
                    seen.add(key)
                    first.append(i)
        done = dict(zip(first, self.inner.map([genomes[i] for i in first], generation)))
        failed = {g: error for g, error in self.failures}
        results = []
        self.asked += len(genomes)
        for i, (g, key) in enumerate(zip(genomes, keys)):
            if i in done:
                ev = done[i]
                if not ev.failed and key not in self._store:
                    self._store[key] = ev
                results.append(ev)
                continue
            stored = self._store.get(key)
            if stored is None:  # its team's evaluation in this generation failed
                source = next(genomes[j].key for j in first if keys[j] == key)
                error = failed.get(source, "evaluation failed")
                self.failures.append((g.key, f"same team as genome {source}: {error}"))
                results.append(Evaluation.failure(error))
                continue
            self.reused += 1
            results.append(replace(stored, steps=0, seconds_env=0.0, seconds_controller=0.0, seconds_decode=0.0))
        return results

    def rebuilds(self, generation: int) -> bool:
        return getattr(self.inner, "rebuilds", lambda _: False)(generation)

    def check(self, record: dict[str, Any]) -> dict[str, Any]:
        return self.inner.check(record)

    def close(self) -> None:
        self.inner.close()


__all__ = ["ReusingEvaluator", "team_key"]
