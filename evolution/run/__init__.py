"""Running an experiment: from an experiment file to statistics, champions and checkpoints.

``experiment`` (TOML experiment files, overrides, presets), ``trainer`` (the generation loop),
``evaluate`` (a genome's trials through the environment's API), ``backends`` (serial,
process-pool and Ray evaluation), ``checkpoint``, ``stats``, ``champion`` (the files a run
writes), ``plots`` (the run's figure).
"""
