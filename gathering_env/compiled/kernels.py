"""Compiled (numba) kernels of the simulation step: everything but pymunk's own calls.

Three kernels, each over a batch of W independent worlds of the same configuration
(a single episode is W = 1):

* ``drive``: wheel clipping, collision avoidance, attached-robot drive and the
  differential-drive control velocities, written straight into the per-world velocity
  arrays that ``pymunk.batch.set_space_bodies`` reads.
* ``settle``: after the physics step, unpack the bodies' poses from pymunk's batch buffer,
  find gathered blocks, run the pickup heuristic (attach decisions and releases, reported
  as events for the few pymunk joint calls), and optionally ``sense``.
* ``sense``: the readings of every sensor of every robot of every world.

Each kernel is a plain loop (worlds x robots x objects x sensors) and reproduces the
numpy reference (``gathering_env.reference.sensing``, ``heuristics``, ``scoring`` and
``GatheringWorld``) operation for operation, so both give the same numbers; the tests
compare them. Geometry and readings are documented in ``gathering_env.reference.sensing``.

Kernels are compiled on first use and cached on disk (``cache=True``), so later imports,
and process-pool workers, load the machine code instead of compiling again.

The kernels live one concern to a module beside this one: ``drive.py`` (``drive``),
``settle.py`` (``settle``, ``gathered_blocks``), ``sensing.py`` (``sense``,
``CompiledSensorBank``) and ``tables.py`` (the sensor table, the parameter and flag vectors
and the event codes they share); this module gathers them under one name for the engine.
"""

from __future__ import annotations

from .drive import drive
from .sensing import CompiledSensorBank, sense
from .settle import gathered_blocks, settle, unpack
from .tables import EV_ATTACH, EV_RELEASE, sensor_table, world_params

__all__ = ["CompiledSensorBank", "EV_ATTACH", "EV_RELEASE", "drive", "gathered_blocks", "sense",
           "sensor_table", "settle", "unpack", "world_params"]
