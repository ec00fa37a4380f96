"""The shipped presets: the paper's experiment files (S1-S3, M1-M3), a quick demo and the
neat-python configs. pip installs this folder as the package ``evolution.presets``
(see pyproject.toml); ``evolution.run.presets.presets_dir()`` finds it in a checkout and in
an installed wheel alike.
"""
