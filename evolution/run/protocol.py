"""Protocols: named bundles of world and method options (``protocol = "original"``).

The project follows the paper's text by default. The paper's published numbers, however,
came from its 2018 Java code, which differs from the text in ways the results depend on.
``protocol = "original"`` in ``[experiment]`` (or ``gathering-evolve --protocol original``)
sets every option that reproduces that code; each option is an ordinary key and can also be
set on its own, without naming a protocol:

============================  ==================  ================================================
key                           paper (default)     original
============================  ==================  ================================================
``[experiment] layout``       ``"per_trial"``     ``"per_run"``: one layout for every trial of
                                                  every genome of every generation (the run's
                                                  seed); the trials are then one episode, run once
``[experiment] elitism``      ``"species"``       ``"ratchet"``: the best-ever genome is
                                                  carried over, unchanged and never re-scored
                                                  (with Encog's selection its species elites too)
``[experiment] complexity``   ``"paper"``         ``"original"``: eq. 2 as the code computed it
``[experiment] speciation``   (the neat config's  ``"original"``: Encog's distance and threshold
                              ``species_mode``)   rule (``evolution.reproduction.species``); in SO
                                                  also Encog's species of leaders, offspring
                                                  shares, no species elites (the 2018 code's
                                                  rate 0) and stagnation 15
                                                  (``evolution.reproduction.breeding``)
``[environment] zone_depth``  8                   4 (zone 20 x 4)
``[environment] pickup_box``  ``"front"``         ``"centre"``, 0.1 forward x 0.2 across
``[environment] ir_response`` ``"linear"``        ``"gamma"`` (the Khepera-like curve)
``[environment]               ``"threshold"``     ``"mass"``: kinetic Coulomb friction 0.1 m g
ground_friction``                                 whatever the robots needed (docs/fidelity.md)
``[environment] robot_,       0, 0, 0             1, 0.4, 1 (Box2D's: a contact takes the larger)
block_, wall_restitution``
``[environment]               1.0, 0.5            3.63, 0.637: the original robot's net push at a
robot_drive_force,                                standstill (5 from the wheels less its own
robot_max_speed``                                 kinetic friction 1.37) and its top speed
                                                  heading +y (measured on its own classes)
``[environment]               0                   0.28: weaker wheel commands do nothing (the
drive_dead_band``                                 original robot's own ground friction)
``[substrate] decode_window`` 1                   0.2 (middle 20 % of range, FOV, orientation)
``[substrate] bias_threshold`` false              true (biases thresholded like link weights)
============================  ==================  ================================================

(The time bonus 20, the 5 trials of 10 000 steps, the sensor-type bands' order and the weld that
seats the robot are the paper's and the 2018 code's alike, so they are not in the bundle.)

``protocol = "paper"`` names the defaults. A file that names a protocol and sets one of its
keys to another value is refused (``ExperimentError`` naming the file and key); without a
``protocol`` key every option is free.
"""

from __future__ import annotations

from typing import Any

#: Protocol name -> {section: {key: value}}; the "paper" values are the defaults of the
#: dataclasses that own the keys (``Experiment``, ``WorldConfig``, ``Substrate``).
ORIGINAL: dict[str, dict[str, Any]] = {
    "experiment": {"layout": "per_run", "elitism": "ratchet", "complexity": "original", "speciation": "original"},
    "environment": {"zone_depth": 4.0, "pickup_box": "centre", "pickup_box_width": 0.2, "pickup_box_depth": 0.1,
                    "ir_response": "gamma", "ground_friction": "mass", "robot_restitution": 1.0,
                    "block_restitution": 0.4, "wall_restitution": 1.0, "robot_drive_force": 3.63,
                    "robot_max_speed": 0.637, "drive_dead_band": 0.28},
    "substrate": {"decode_window": 0.2, "bias_threshold": True},
}

#: The world keys of the bundle that are physics (friction, restitution, drive), for scenes
#: that compare the original's pushing with this simulator's (examples/physics_scenes.py).
ORIGINAL_PHYSICS = ("ground_friction", "robot_restitution", "block_restitution", "wall_restitution",
                    "robot_drive_force", "robot_max_speed", "drive_dead_band")

#: The original's robot as ``drive_model = "force"`` models it (not part of the bundle yet: the
#: S1-original evidence was run with the velocity drive's keys above). It replaces the
#: velocity drive's three keys: ``robot_drive_force``, ``robot_max_speed``, ``drive_dead_band``.
ORIGINAL_FORCE_DRIVE = {"drive_model": "force", "damping": 0.1}

#: The original's MASON schedule on top of the force drive (not part of the bundle either):
#: robots and the physics step shuffled every step (``gathering_env.drive.shuffled_times``).
ORIGINAL_SCHEDULE = {"schedule": "shuffled"}

PROTOCOLS = ("paper", "original")

#: One line per protocol, for ``gathering-evolve --list``.
DESCRIPTIONS = {
    "paper": "the paper's text (the defaults)",
    "original": "the 2018 Java code that produced the published figures: one layout per run, ratchet on the best "
                "genome, zone 20 x 4, pickup box at the robot's centre, 20 % decoding window, its eq. 2, its "
                "physics (mass friction, bouncing contacts, its robot's push, speed and dead band)",
}


def _paper_values() -> dict[str, dict[str, Any]]:
    from dataclasses import fields

    from evolution.encodings.substrate import Substrate
    from evolution.run.experiment import Experiment
    from gathering_env.config import WorldConfig

    owners = {"experiment": Experiment, "environment": WorldConfig, "substrate": Substrate}
    values: dict[str, dict[str, Any]] = {}
    for section, keys in ORIGINAL.items():
        defaults = {f.name: f.default for f in fields(owners[section])}
        values[section] = {key: defaults[key] for key in keys}
    return values


def protocol_values(name: str) -> dict[str, dict[str, Any]]:
    """{section: {key: value}} of a protocol (raises ``ValueError`` for an unknown name)."""
    if name not in PROTOCOLS:
        raise ValueError(f"protocol={name!r}; allowed: {list(PROTOCOLS)}")
    values = ORIGINAL if name == "original" else _paper_values()
    return {section: dict(keys) for section, keys in values.items()}


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return list(a) == list(b)
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    return a == b


def apply_protocol(name: str, sections: dict[str, dict[str, Any]], source: str,
                   method: str = "hyperneat-m") -> None:
    """Fill ``sections`` (experiment / environment / substrate, changed in place) with the
    protocol's values; a key already set to another value raises ``ValueError`` naming
    ``source``, the section and the key. Substrate keys only apply to HyperNEAT-M."""
    for section, keys in protocol_values(name).items():
        if section == "substrate" and method != "hyperneat-m":
            continue
        target = sections[section]
        for key, value in keys.items():
            if value is None:  # the paper's "speciation": whatever the neat config says
                if target.get(key) is not None:
                    raise ValueError(f"{source}: [{section}] {key} = {target[key]!r} contradicts protocol = "
                                     f"{name!r}; allowed: no {key} key (the neat config's own)")
                continue
            if key in target and not _same(target[key], value):
                raise ValueError(f"{source}: [{section}] {key} = {target[key]!r} contradicts protocol = {name!r}; "
                                 f"allowed: {value!r} (or no protocol key, to set it on its own)")
            target[key] = list(value) if isinstance(value, list) else value


__all__ = ["DESCRIPTIONS", "ORIGINAL", "ORIGINAL_FORCE_DRIVE", "ORIGINAL_PHYSICS", "ORIGINAL_SCHEDULE", "PROTOCOLS", "apply_protocol", "protocol_values"]
