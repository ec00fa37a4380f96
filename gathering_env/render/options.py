"""Render options: ``RenderOptions`` (what a frame shows), their validation and bounds.

``RenderOptions.checked`` validates every option (``parse_cones``, ``parse_view`` and the
integer/bool checks) and raises ``RenderOptionError`` (a ValueError) naming the option, the
problem and the allowed values, so CLIs can print one line. The options are described in the
package docstring (``gathering_env.render``) and ``docs/rendering.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

DEFAULT_SIZE_PX = 640
MIN_SIZE_PX, MAX_SIZE_PX = 64, 4096
"""Bounds of ``size_px``: a 4096-pixel frame (with its panel) is about 70 MB in pygame and numpy;
larger sizes end in pygame's out-of-memory error instead of a picture."""
DEFAULT_MIN_ROBOT_PX = 4
AUTO_CONES_COVER = 0.5
"""``cones="auto"`` shows every robot's cones while their summed area is at most this
fraction of the arena's area, else one robot's."""
FOLLOW_SPAN = 10.0
"""Width (world units) of the square a ``follow:K`` view shows around robot K."""
ZONE_MARGIN = 3.0
"""World units shown around the zone in the ``zone`` view."""
VIEWS = ("full", "zone", "follow:K")
CONE_CHOICES = ("auto", "all", "none")


class RenderOptionError(ValueError):
    """A bad render option. ``option``, ``problem`` and ``allowed`` are kept apart for CLIs."""

    def __init__(self, option: str, problem: str, allowed: str) -> None:
        self.option, self.problem, self.allowed = option, problem, allowed
        super().__init__(f"{option}: {problem}; allowed: {allowed}")


def _is_int(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def parse_cones(value: Any, num_robots: int) -> str | tuple[int, ...]:
    """``"auto" | "all" | "none"`` or robot indices (a list, or a string like ``"0,3"``)."""
    allowed = f"'auto', 'all', 'none' or robot indices in 0..{num_robots - 1} (e.g. [3] or '0,3')"
    if isinstance(value, str):
        text = value.strip()
        if text in CONE_CHOICES:
            return text
        try:
            value = [int(part) for part in text.split(",")]
        except ValueError:
            raise RenderOptionError("cones", f"{text!r} is not a choice nor a list of robot indices",
                                    allowed) from None
    if not isinstance(value, (list, tuple, np.ndarray)) or not all(_is_int(i) for i in value):
        raise RenderOptionError("cones", f"{value!r} is not a choice nor a list of robot indices", allowed)
    indices = tuple(sorted({int(i) for i in value}))
    bad = [i for i in indices if not 0 <= i < num_robots]
    if bad:
        raise RenderOptionError("cones", f"robot index {bad[0]} does not exist ({num_robots} robots)", allowed)
    return indices


def parse_view(value: Any, num_robots: int) -> str:
    """``"full"``, ``"zone"`` or ``"follow:K"`` with K a robot index; returns it normalised."""
    allowed = f"'full', 'zone' or 'follow:K' with K in 0..{num_robots - 1}"
    if isinstance(value, str):
        text = value.strip()
        if text in ("full", "zone"):
            return text
        if text.startswith("follow:"):
            try:
                k = int(text[len("follow:"):])
            except ValueError:
                raise RenderOptionError("view", f"{text!r} does not name a robot index", allowed) from None
            if not 0 <= k < num_robots:
                raise RenderOptionError("view", f"robot {k} does not exist ({num_robots} robots)", allowed)
            return f"follow:{k}"
    raise RenderOptionError("view", f"{value!r} is not a view", allowed)


@dataclass(frozen=True)
class RenderOptions:
    """What a frame shows (see ``gathering_env.render``). Build with ``RenderOptions.checked``."""

    size_px: int = DEFAULT_SIZE_PX
    cones: str | tuple[int, ...] = "auto"
    view: str = "full"
    trail: int = 0
    panel: bool = True
    min_robot_px: int = DEFAULT_MIN_ROBOT_PX

    @classmethod
    def checked(cls, num_robots: int, base: RenderOptions | None = None, **options: Any) -> RenderOptions:
        """``base`` (default: the defaults) with ``options`` replaced, each validated.

        Raises:
            RenderOptionError (a ValueError) naming the option and the allowed values.
        """
        names = [f.name for f in cls.__dataclass_fields__.values()]
        unknown = sorted(set(options) - set(names))
        if unknown:
            raise RenderOptionError(unknown[0], "unknown render option", ", ".join(names))
        values: dict[str, Any] = {}
        for name, value in options.items():
            if name == "size_px":
                if not _is_int(value) or not MIN_SIZE_PX <= value <= MAX_SIZE_PX:
                    raise RenderOptionError("size_px", f"{value!r} is not an integer in {MIN_SIZE_PX}..{MAX_SIZE_PX}",
                                            f"an integer in {MIN_SIZE_PX}..{MAX_SIZE_PX} (pixels)")
                value = int(value)
            elif name == "cones":
                value = parse_cones(value, num_robots)
            elif name == "view":
                value = parse_view(value, num_robots)
            elif name == "trail":
                if not _is_int(value) or value < 0:
                    raise RenderOptionError("trail", f"{value!r} is not an integer >= 0",
                                            "an integer >= 0 (steps; 0 = no trails)")
                value = int(value)
            elif name == "panel":
                if not isinstance(value, (bool, np.bool_)):
                    raise RenderOptionError("panel", f"{value!r} is not a bool", "True or False")
                value = bool(value)
            elif name == "min_robot_px":
                if not _is_int(value) or value < 1:
                    raise RenderOptionError("min_robot_px", f"{value!r} is not an integer >= 1", "an integer >= 1")
                value = int(value)
            values[name] = value
        return replace(base if base is not None else cls(), **values)

    @property
    def follow(self) -> int | None:
        """The followed robot of a ``follow:K`` view, else None."""
        return int(self.view.split(":")[1]) if self.view.startswith("follow:") else None
