"""Presets: the shipped experiment files and neat-python configs, by name.

The top-level ``configs/`` folder of the repository is installed as the package
``evolution.presets`` (``[tool.setuptools.package-dir]`` in pyproject.toml), so the shipped
experiment files and neat configs are there after ``pip install`` too. ``presets_dir()`` finds
them; ``preset_names()``, ``preset_path(name)`` and ``preset_description(name)`` name them (the
description is the first sentence of the file's opening comment). The paper's six experiments
are also shipped under every other protocol as ``<name>-<protocol>`` (``S1-original``): the
same file with the protocol added (``resolve_preset``, ``preset_text``).

A name that is no preset raises ``evolution.run.experiment.ExperimentError`` listing the known ones.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path
from typing import Any

from evolution.run.protocol import PROTOCOLS

DEFAULT_NEAT_CONFIGS = {"hyperneat-m": "hyperneat_m.neat.cfg", "neat-m": "neat_m.neat.cfg"}
PRESET_PACKAGE = "evolution.presets"


def _error(message: str) -> ValueError:
    from evolution.run.experiment import ExperimentError  # the experiment module imports this one

    return ExperimentError(message)


def presets_dir() -> Path:
    """The folder of shipped presets (experiment files and neat configs).

    In a source checkout (also an editable install) it is the checkout's ``configs/``
    folder; in an installed wheel, the package ``evolution.presets`` that setuptools
    built from that folder.
    """
    checkout = Path(__file__).resolve().parents[2]  # evolution/run/presets.py -> the checkout
    if (checkout / "pyproject.toml").is_file() and (checkout / "configs" / "__init__.py").is_file():
        return checkout / "configs"
    return Path(str(resources.files(PRESET_PACKAGE)))


CONFIG_DIR = presets_dir()


def preset_names() -> list[str]:
    """Names of the shipped experiment presets (the ``*.toml`` files, without suffix)."""
    return sorted(p.stem for p in CONFIG_DIR.glob("*.toml"))


PROTOCOL_EXPERIMENTS = ("S1", "S2", "S3", "M1", "M2", "M3")
"""The paper's experiments, also shipped under every other protocol as ``<name>-<protocol>``."""


def protocol_preset_names() -> list[str]:
    """The paper's experiments under the other protocols: ``S1-original`` ... ``M3-original``."""
    return [f"{name}-{protocol}" for protocol in PROTOCOLS if protocol != "paper" for name in PROTOCOL_EXPERIMENTS]


def resolve_preset(name: str) -> tuple[Path, dict[str, Any]]:
    """(file, overrides) of an experiment preset: ``S1`` is ``configs/S1.toml``; ``S1-original``
    is the same file with ``protocol = "original"`` and ``name = "S1-original"``.

    Raises:
        ExperimentError: no such preset; the one-line message lists the known ones.
    """
    if name in protocol_preset_names():
        base, protocol = name.split("-", 1)
        return CONFIG_DIR / f"{base}.toml", {"protocol": protocol, "name": name}
    known = preset_names() + protocol_preset_names()
    if name not in known:
        raise _error(f"{name}: unknown preset; known: {', '.join(known)} (or the path of an experiment file)")
    return CONFIG_DIR / f"{name}.toml", {}


def preset_text(name: str) -> str:
    """The TOML text of a preset (what ``--dump`` prints); a protocol preset is its base file
    with the ``protocol`` key added and its name changed, so that the text loads to the preset."""
    if name not in protocol_preset_names():
        return preset_path(name, neat_configs=True).read_text(encoding="utf-8")
    path, overrides = resolve_preset(name)
    lines = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("name ="):
            line = f'name = "{overrides["name"]}"'
        lines.append(line)
        if line.strip() == "[experiment]":
            lines.append(f'protocol = "{overrides["protocol"]}"   # evolution.run.protocol')
    return f"# {name}: {protocol_preset_description(name)}\n" + "\n".join(lines) + "\n"


def protocol_preset_description(name: str) -> str:
    """One line: which paper experiment under which protocol."""
    base, protocol = name.split("-", 1)
    return f"experiment {base} of the paper under protocol = \"{protocol}\" (as the published runs were made)."


def neat_config_names() -> list[str]:
    """File names of the shipped neat-python configs."""
    return sorted(p.name for p in CONFIG_DIR.glob("*.neat.cfg"))


def preset_path(name: str, neat_configs: bool = False) -> Path:
    """The file of an experiment preset (``S1``), or with ``neat_configs`` also of a shipped
    neat config by file name (``hyperneat_m.neat.cfg``).

    Raises:
        ExperimentError: no such preset; the one-line message lists the known ones.
    """
    known = preset_names() + (neat_config_names() if neat_configs else [])
    if name not in known:
        raise _error(f"{name}: unknown preset; known: {', '.join(known)} "
                              f"(or the path of an experiment file)")
    return CONFIG_DIR / (name if name.endswith(".cfg") else f"{name}.toml")


def preset_description(name: str) -> str:
    """The one-line description of a preset: the first sentence of its opening comment."""
    lines = preset_path(name, neat_configs=True).read_text(encoding="utf-8").splitlines()
    comment = []
    for line in lines:
        if not line.startswith("#"):
            break
        comment.append(line.lstrip("#").strip())
    text = " ".join(comment)
    end = re.search(r"\.(\s|$)", text)
    return text[: end.start() + 1] if end else text


def is_preset_name(arg: str) -> bool:
    """Whether a command-line EXPERIMENT argument means a preset rather than a file.

    A preset name has no path separator and no ``.toml`` suffix and is not an existing file,
    nor an existing folder unless it is a shipped preset's name; anything else is a path (so a
    folder is reported as a folder, not as an unknown preset).
    """
    if any(sep in arg for sep in "/\\") or arg.endswith(".toml") or Path(arg).is_file():
        return False
    return arg in preset_names() or not Path(arg).exists()


__all__ = ["CONFIG_DIR", "DEFAULT_NEAT_CONFIGS", "PRESET_PACKAGE", "PROTOCOL_EXPERIMENTS", "is_preset_name",
           "neat_config_names", "preset_description", "preset_names", "preset_path", "preset_text",
           "presets_dir", "protocol_preset_description", "protocol_preset_names", "resolve_preset"]
