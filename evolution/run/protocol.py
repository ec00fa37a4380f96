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
                                                  seed); the trials differ by their schedules
``[experiment] elitism``      ``"species"``       ``"ratchet"``: the best-ever genome is
                                                  carried over, unchanged and never re-scored
                                                  (with Encog's selection its species elites too)
``[experiment] complexity``   ``"paper"``         ``"original"``: eq. 2 as the code computed it
``[experiment] truncation``   ``"neat"``          ``"encog"``: Encog's truncation, the best
                                                  max(floor(0.3 n), 1) of a species breed
                                                  (``evolution.reproduction.breeding``)
``[experiment] weights``      ``"neat"``          ``"encog"``: link weights uniform in +-5 and
                                                  Encog's weight operations
                                                  (``evolution.reproduction.encog``)
``[experiment] speciation``   (the neat config's  ``"original"``: Encog's distance and threshold
                              ``species_mode``)   rule (``evolution.reproduction.species``); in SO
                                                  also Encog's species of leaders, offspring
                                                  shares, no species elites (the 2018 code's
                                                  rate 0) and stagnation 15
                                                  (``evolution.reproduction.breeding``)
``[experiment]                ``"membership"``    ``"encog"`` (version 10, SO): Encog's species
species_bookkeeping``                             pointers, zombie species, speciation after
                                                  scoring, its generation 0
                                                  (``evolution.reproduction.bookkeeping``)
``[environment] zone_depth``  8                   4 (zone 20 x 4)
``[environment] pickup_box``  ``"front"``         ``"centre"``, 0.1 forward x 0.2 across
``[environment] ir_response`` ``"linear"``        ``"gamma"`` (a steeper curve; versions 1-7),
                                                  ``"khepera"`` (the original's curve, version 8)
``[environment]               ``"linear"``        ``"khepera"`` (version 8): the original's bottom
bottom_response``                                 sensor, on/off at the robot's front
``[environment]               ``"nearer"``        ``"farther"``: the colour reading rises with
colour_response``                                 distance (block 0.5 + d/2R, wall d/2R)
``[environment]               ``"cone"``          ``"rays"``: a cone sensor sees a block only
block_sighting``                                  along its axis and its two edges (three rays)
``[environment]               ``"nearest"``       ``"original"`` (version 9): a wall is read at
wall_distance``                                   the distance the 2018 formulas give
``[environment]               ``"threshold"``     ``"mass"``: kinetic Coulomb friction 0.1 m g
ground_friction``                                 whatever the robots needed (docs/fidelity.md)
``[environment]               ``"sharp"``         ``"original"`` (version 11): a robot welded to a
attached_steering``                               block slows its inner wheel to 0 at 90 degrees
                                                  off the zone centre, not at 45
``[environment] weld_spin``   ``"held"``          ``"free"`` (version 11): a welded robot's
                                                  friction torque lets go, so the pair can turn
``[environment] robot_,       0, 0, 0             1, 0.4, 1 (Box2D's: a contact takes the larger)
block_, wall_restitution``
``[environment] drive_model,  ``"velocity"``, 0   ``"force"``, 0.1: the original robot (wheel
damping``                                         forces, traction impulse, its own ground
                                                  friction; ``gathering_env.drive``)
``[environment] schedule``    ``"fixed"``         ``"shuffled"``: MASON's order, robots and the
                                                  physics step shuffled every step
``[substrate] decode_window`` 1                   0.2 (middle 20 % of range, FOV, orientation)
``[substrate] bias_threshold`` false              true (biases thresholded like link weights)
``[substrate] bearings``      ``"atan2"``         ``"atan"``: the 2018 decoder's atan(y / x), every
                                                  sensor on the front half of the body
============================  ==================  ================================================

(The time bonus 20, the 5 trials of 10 000 steps, the sensor-type bands' order and the weld that
seats the robot are the paper's and the 2018 code's alike, so they are not in the bundle.)

**Versions.** A bundle that is found to differ from the code it names is corrected in a new
version, never in place, so that every run made under an earlier one still resumes and rebuilds
to the same numbers. ``protocol_version`` in ``[experiment]`` picks one (default: the newest);
``experiment.json`` records the version a run used. A saved experiment from before versions
(one that names a protocol but no version) holds every key its bundle set, so its version is the
newest one whose keys it holds with the same values (``saved_version``). The original's:

1. (2026-11) the method, zone, pickup box, IR curve and substrate keys, in this simulator's
   default physics (the velocity drive at its defaults, a fixed order).
2. (2026-11) adds the original's contacts (mass ground friction, restitutions) and its robot as
   the velocity drive models it: net push at a standstill 3.63, top speed 0.637, dead band 0.28
   (``robot_drive_force``, ``robot_max_speed``, ``drive_dead_band``). With a fixed order the
   simulator is deterministic, so each genome ran its one layout once.
3. (2026-12) the original robot itself (``drive_model = "force"``, ``damping = 0.1``)
   in place of version 2's velocity-drive keys, and its MASON schedule (``schedule =
   "shuffled"``): with these the scripted pushing scenes match the original's own classes, and
   the run's trials share its layout and differ by schedule, as the original's five did.
4. (2026-12) adds Encog's breeding as the 2018 code configured it: its truncation
   (``truncation = "encog"``: ``TruncationSelection(0.3)`` keeps max(floor(0.3 n), 1) of a
   species as parents where the earlier versions kept ceil(0.3 n) and at least two, so a
   species of fewer than 7 genomes breeds from its best genome alone, by mutation) and its link
   weights (``weights = "encog"``: uniform in +-5 where the earlier versions drew N(0, 1) clamped
   to +-3; perturbations of deviation 0.02 or 1 (NEAT-M 0.004 or 0.2) where they used 0.5).
5. (2026-12) adds the 2018 decoder's sensor bearings (``[substrate] bearings = "atan"``): it
   placed a HyperNEAT-M sensor at atan(y / x) of its input node, so the nodes behind the body
   carry their sensors on the front half (at their angle minus pi) and every sensor of the
   original's robots faces forward, where versions 1-4 placed them all round (atan2).
6. (2026-12) adds the 2018 code's colour reading (``[environment] colour_response =
   "farther"``): its colour sensor read a block as 0.5 + d / 2R and a wall as d / 2R (d the
   distance, R the range), rising with distance, where versions 1-5 read 1 - d / R in its place
   (nearer = higher); a wall at contact then reads 0, as nothing does.
7. (2026-12) adds the 2018 simulator's block sighting (``[environment]
   block_sighting = "rays"``): its cone sensors find a block (a Box2D polygon) by three ray casts,
   the axis and the two cone edges, so a block lying in the cone between them is unseen, where
   versions 1-6 saw any block whose nearest point lies in the cone.
8. (2026-12) adds the 2018 simulator's Khepera proximity curve (``gathering_env.khepera``)
   for the infrared sensor (``ir_response = "khepera"``: a Gamma density, 0 at contact, 1 at
   1.3-1.8 % of the range, nearly 0 beyond 9 %, where versions 1-7 used (1 - d/R) ** 3, which
   they took for it) and for the bottom sensor (``bottom_response = "khepera"``: a disc ahead of
   the centre, on over the zone and off within about 0.01 of it, where versions 1-7 read the
   centre with a 1-unit falloff).
9. (2026-12) adds the 2018 simulator's wall distances (``wall_distance =
   "original"``): its sensors read a wall they see at the distance its line formulas give
   (``gathering_env.reference.sensing.original_wall_distance``), which mix the sensor's frame with
   the world's, where versions 1-8 read the wall's nearest point in the cone.
10. (2026-12) adds Encog's species bookkeeping (``species_bookkeeping = "encog"``,
    single-objective runs): the best species is the one the best genome *points at* (a pointer
    set when a genome joins a species, inherited by mutants), which survives its leader's death;
    a population is speciated after it is scored (leaders change during the pass); generation
    0 is speciated at 0.99, nearly a species per genome, and the ratchet starts from its first
    genome. Versions 1-9 named species by membership (``evolution.reproduction.bookkeeping``).
11. (2026-12, the newest) adds the 2018 code's welded robot: its steering (``attached_steering =
    "original"``, its ``Heuristic``: outer wheel at full power, inner at 1 - 2|e|/pi for a heading
    error e off the zone centre, stopped only at 90 degrees where versions 1-10 stopped it from
    45) and a pair that turns (``weld_spin = "free"``: the robot's ground-friction torque lets go
    while it is welded). Measured on the original's own classes, a robot welded to a small block
    27.5 degrees off course arcs it into the zone in 943 steps whatever the robot's friction
    torque; in versions 1-10 the pair never turned and drove straight on until it stalled 90
    degrees off (``gathering_env.attachments``; docs/fidelity.md, "gripped-block steering").

``protocol = "paper"`` names the defaults (one version). A file that names a protocol and sets
one of its keys to another value is refused (``ExperimentError`` naming the file and key);
without a ``protocol`` key every option is free.
"""

from __future__ import annotations

from typing import Any

_METHOD = {"layout": "per_run", "elitism": "ratchet", "complexity": "original", "speciation": "original"}
_SENSING = {"zone_depth": 4.0, "pickup_box": "centre", "pickup_box_width": 0.2, "pickup_box_depth": 0.1,
            "ir_response": "gamma"}
_CONTACTS = {"ground_friction": "mass", "robot_restitution": 1.0, "block_restitution": 0.4, "wall_restitution": 1.0}
_SUBSTRATE = {"decode_window": 0.2, "bias_threshold": True}

#: The original's robot as the velocity drive models it (version 2): its net push at a
#: standstill, top speed heading +y and dead band, measured on its own classes.
ORIGINAL_VELOCITY_DRIVE = {"robot_drive_force": 3.63, "robot_max_speed": 0.637, "drive_dead_band": 0.28}

#: The original's robot itself (``gathering_env.drive``, ``drive_model = "force"``).
ORIGINAL_FORCE_DRIVE = {"drive_model": "force", "damping": 0.1}

#: The original's MASON schedule, on top of the force drive (``gathering_env.drive.shuffled_times``).
ORIGINAL_SCHEDULE = {"schedule": "shuffled"}

#: Encog's breeding as the 2018 code set it up (version 4): its truncation selection
#: (``evolution.reproduction.breeding.truncate``) and link weights (``evolution.reproduction.encog``).
ORIGINAL_BREEDING = {"truncation": "encog", "weights": "encog"}

#: The 2018 decoder's sensor bearings (version 5; ``evolution.encodings.substrate``).
ORIGINAL_BEARINGS = {"bearings": "atan"}

#: The 2018 code's colour reading (version 6; ``gathering_env.reference.sensing``).
ORIGINAL_COLOUR = {"colour_response": "farther"}

#: The 2018 simulator's block sighting (version 7; ``gathering_env.reference.sensing.ray_sighting``).
ORIGINAL_SIGHTING = {"block_sighting": "rays"}

#: The 2018 simulator's Khepera proximity curve for the infrared and bottom sensors (version 8;
#: ``gathering_env.khepera``).
ORIGINAL_KHEPERA = {"ir_response": "khepera", "bottom_response": "khepera"}

#: The 2018 simulator's wall distances (version 9; ``gathering_env.reference.sensing``).
ORIGINAL_WALLS = {"wall_distance": "original"}

#: Encog's species bookkeeping (version 10; ``evolution.reproduction.bookkeeping``).
ORIGINAL_BOOKS = {"species_bookkeeping": "encog"}

#: The 2018 code's welded robot (version 11): its steering (``Heuristic``;
#: ``gathering_env.reference.heuristics.attached_wheels``) and a pair that turns (``weld_spin``).
ORIGINAL_WELDED = {"attached_steering": "original", "weld_spin": "free"}

#: Protocol name -> version -> {section: {key: value}}; the "paper" values are the defaults of
#: the dataclasses that own the keys (``Experiment``, ``WorldConfig``, ``Substrate``), filled in
#: by ``protocol_values``.
BUNDLES: dict[str, dict[int, dict[str, dict[str, Any]]]] = {
    "original": {
        1: {"experiment": _METHOD, "environment": _SENSING, "substrate": _SUBSTRATE},
        2: {"experiment": _METHOD, "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_VELOCITY_DRIVE},
            "substrate": _SUBSTRATE},
        3: {"experiment": _METHOD, "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE,
                                                   **ORIGINAL_SCHEDULE},
            "substrate": _SUBSTRATE},
        4: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE},
            "substrate": _SUBSTRATE},
        5: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE},
            "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        6: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR},
            "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        7: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR,
                            **ORIGINAL_SIGHTING},
            "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        8: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR,
                            **ORIGINAL_SIGHTING, **ORIGINAL_KHEPERA},
            "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        9: {"experiment": {**_METHOD, **ORIGINAL_BREEDING},
            "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR,
                            **ORIGINAL_SIGHTING, **ORIGINAL_KHEPERA, **ORIGINAL_WALLS},
            "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        10: {"experiment": {**_METHOD, **ORIGINAL_BREEDING, **ORIGINAL_BOOKS},
             "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR,
                             **ORIGINAL_SIGHTING, **ORIGINAL_KHEPERA, **ORIGINAL_WALLS},
             "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
        11: {"experiment": {**_METHOD, **ORIGINAL_BREEDING, **ORIGINAL_BOOKS},
             "environment": {**_SENSING, **_CONTACTS, **ORIGINAL_FORCE_DRIVE, **ORIGINAL_SCHEDULE, **ORIGINAL_COLOUR,
                             **ORIGINAL_SIGHTING, **ORIGINAL_KHEPERA, **ORIGINAL_WALLS, **ORIGINAL_WELDED},
             "substrate": {**_SUBSTRATE, **ORIGINAL_BEARINGS}},
    },
    "paper": {1: {}},
}

PROTOCOLS = ("paper", "original")

#: The original protocol's newest bundle (what ``protocol = "original"`` sets).
ORIGINAL = BUNDLES["original"][max(BUNDLES["original"])]

#: The world keys of the bundles that are physics (friction, restitution, drive), for scenes
#: that compare the original's pushing with this simulator's (examples/physics_scenes.py).
ORIGINAL_PHYSICS = (*_CONTACTS, *ORIGINAL_VELOCITY_DRIVE)

#: One line per protocol, for ``gathering-evolve --list``.
DESCRIPTIONS = {
    "paper": "the paper's text (the defaults)",
    "original": "the 2018 Java code that produced the published figures: one layout per run, ratchet on the best "
                "genome, Encog's truncation and link weights, zone 20 x 4, pickup box at the robot's centre, 20 % decoding window, its "
                "sensor bearings (all on the front half), its colour reading (rising with distance), block sighting (three rays), wall distances and Khepera curve (infrared, bottom), its eq. 2, Encog's species bookkeeping, its "
                "welded robot (its steering, a pair that turns), its "
                "physics (mass friction, bouncing contacts) and its robot on its shuffled schedule",
}


def versions(name: str) -> tuple[int, ...]:
    """The versions of a protocol, oldest first (raises ``ValueError`` for an unknown name)."""
    if name not in PROTOCOLS:
        raise ValueError(f"protocol={name!r}; allowed: {list(PROTOCOLS)}")
    return tuple(sorted(BUNDLES[name]))


def newest_version(name: str) -> int:
    """The version ``protocol = name`` means when no ``protocol_version`` is given."""
    return versions(name)[-1]


def saved_version(name: str, sections: dict[str, dict[str, Any]]) -> int:
    """The version of ``name`` that a saved experiment from before versions was run under: the
    newest whose every key ``sections`` holds with the bundle's value (each version of a bundle
    sets keys or values the one before did not, and a run saved every key its bundle set)."""
    for version in reversed(versions(name)):
        bundle = protocol_values(name, version)
        if all(key in sections.get(section, {}) and _same(sections[section][key], value)
               for section, keys in bundle.items() for key, value in keys.items() if value is not None
               if section != "substrate" or sections.get("substrate")):
            return version
    return versions(name)[0]


def _paper_values() -> dict[str, dict[str, Any]]:
    """The defaults of every key any version of any bundle sets."""
    from dataclasses import fields

    from evolution.encodings.substrate import Substrate
    from evolution.run.experiment import Experiment
    from gathering_env.config import WorldConfig

    owners = {"experiment": Experiment, "environment": WorldConfig, "substrate": Substrate}
    values: dict[str, dict[str, Any]] = {}
    for section, owner in owners.items():
        keys = [key for bundles in BUNDLES.values() for bundle in bundles.values() for key in bundle.get(section, {})]
        defaults = {f.name: f.default for f in fields(owner)}
        values[section] = {key: defaults[key] for key in dict.fromkeys(keys)}
    return values


def protocol_values(name: str, version: int | None = None) -> dict[str, dict[str, Any]]:
    """{section: {key: value}} of a protocol's version (default: the newest); raises
    ``ValueError`` for an unknown name or version."""
    known = versions(name)
    version = known[-1] if version is None else version
    if version not in known:
        raise ValueError(f"protocol_version={version!r} for protocol={name!r}; allowed: {list(known)}")
    values = _paper_values() if name == "paper" else BUNDLES[name][version]
    return {section: dict(keys) for section, keys in values.items()}


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return list(a) == list(b)
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    return a == b


def apply_protocol(name: str, sections: dict[str, dict[str, Any]], source: str,
                   method: str = "hyperneat-m", version: int | None = None, fill: bool = True) -> None:
    """Fill ``sections`` (experiment / environment / substrate, changed in place) with the
    values of the protocol's ``version`` (default: the newest); a key already set to another
    value raises ``ValueError`` naming ``source``, the section and the key. Substrate keys only
    apply to HyperNEAT-M. ``fill=False`` only checks: a saved run holds every key its bundle set
    when it ran, and a key the bundle has gained since (``protocol = "paper"`` names the defaults
    of every key of every version) is left out, which gives the same world."""
    label = repr(name) if version in (None, newest_version(name)) else f"{name!r} (version {version})"
    for section, keys in protocol_values(name, version).items():
        if section == "substrate" and method != "hyperneat-m":
            continue
        target = sections[section]
        for key, value in keys.items():
            if value is None:  # the paper's "speciation": whatever the neat config says
                if target.get(key) is not None:
                    raise ValueError(f"{source}: [{section}] {key} = {target[key]!r} contradicts protocol = "
                                     f"{label}; allowed: no {key} key (the neat config's own)")
                continue
            if key in target and not _same(target[key], value):
                raise ValueError(f"{source}: [{section}] {key} = {target[key]!r} contradicts protocol = {label}; "
                                 f"allowed: {value!r} (or no protocol key, to set it on its own)")
            if fill:
                target[key] = list(value) if isinstance(value, list) else value


__all__ = ["BUNDLES", "DESCRIPTIONS", "ORIGINAL", "ORIGINAL_BREEDING", "ORIGINAL_FORCE_DRIVE", "ORIGINAL_PHYSICS", "ORIGINAL_SCHEDULE",
           "ORIGINAL_VELOCITY_DRIVE", "PROTOCOLS", "apply_protocol", "newest_version", "protocol_values", "saved_version",
           "versions"]
