"""Sensor descriptions: the per-type bounds, ``SensorSpec``, ``Morphology`` and complexity.

A *morphology* is the sensor suite every robot of the (homogeneous) team carries: an
ordered list of at most 10 sensors, one observation entry per sensor, in list order.

Angles are radians. ``bearing`` is where the sensor sits on the robot's rim, measured
counter-clockwise from the robot's heading, in [-pi, pi]. ``orientation`` turns the
sensor's axis away from the rim's outward normal, in [-pi/2, pi/2]. ``range`` is in world
units, ``fov`` is the full opening angle of the sensing cone.

The bounds per type (``SENSOR_TYPES``) are docs/model.md §3; the complexity measure is the
paper's eq. 2 (higher = simpler).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

MAX_SENSORS = 10
"""The substrate has 10 input positions, so a morphology holds at most 10 sensors."""


@dataclass(frozen=True)
class SensorType:
    """Bounds of one sensor type. ``range`` is (min_exclusive, max]; ``fov`` is [min, max].

    ``configurable`` is False for the bottom sensor, whose range and FOV are fixed (0).
    """

    name: str
    detects: str
    range_max: float
    fov_min: float
    fov_max: float
    configurable: bool = True
    range_min: float = 0.0


SENSOR_TYPES: dict[str, SensorType] = {
    "infrared": SensorType("infrared", "robots, blocks, walls", 10.0, math.pi / 6, 5 * math.pi / 6),
    "ultrasonic": SensorType("ultrasonic", "robots, blocks, walls", 25.0, 0.1, math.pi),
    "colour": SensorType("colour", "blocks (0.5, 1] vs walls (0, 0.5]", 10.0, math.pi / 6, 5 * math.pi / 6),
    "camera": SensorType("camera", "robots and blocks: cooperation need", 20.0, math.pi / 9, 8 * math.pi / 9),
    "bottom": SensorType("bottom", "gathering zone under the robot", 0.0, 0.0, 0.0, configurable=False),
}
"""Sensor type name -> bounds. Order is stable: it is also the integer code of each type."""

TYPE_CODES: dict[str, int] = {name: i for i, name in enumerate(SENSOR_TYPES)}
"""Sensor type name -> integer code used by the vectorised sensing kernels."""

BEARING_BOUNDS = (-math.pi, math.pi)
ORIENTATION_BOUNDS = (-math.pi / 2, math.pi / 2)


def _number(field_name: str, value: Any, allowed: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"sensor {field_name}={value!r} must be a number; allowed: {allowed}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"sensor {field_name}={value!r} must be finite; allowed: {allowed}")
    return x


@dataclass(frozen=True)
class SensorSpec:
    """One sensor: type, mount bearing, orientation, range and field of view.

    Args:
        type: one of ``SENSOR_TYPES`` ('infrared', 'ultrasonic', 'colour', 'camera', 'bottom').
        bearing: mount position on the rim, radians CCW from the heading, in [-pi, pi].
        orientation: turn of the sensor axis from the outward normal, in [-pi/2, pi/2].
        range: sensing distance from the mount point (units), in (0, max] of the type.
            Bottom sensors have no range (must be 0 or None).
        fov: full cone opening angle (radians), in [min, max] of the type. Bottom: 0/None.

    Raises:
        ValueError: naming the field, the value and the allowed range.
    """

    type: str
    bearing: float = 0.0
    orientation: float = 0.0
    range: float | None = None
    fov: float | None = None

    def __post_init__(self) -> None:
        if self.type not in SENSOR_TYPES:
            raise ValueError(
                f"sensor type={self.type!r} is unknown; allowed: {list(SENSOR_TYPES)}"
            )
        spec = SENSOR_TYPES[self.type]
        lo, hi = BEARING_BOUNDS
        bearing = _number("bearing", self.bearing, f"[{lo:.6g}, {hi:.6g}]")
        if not lo - 1e-12 <= bearing <= hi + 1e-12:
            raise ValueError(f"sensor bearing={bearing!r} out of range; allowed: [{lo:.6g}, {hi:.6g}]")
        lo, hi = ORIENTATION_BOUNDS
        orientation = _number("orientation", self.orientation, f"[{lo:.6g}, {hi:.6g}]")
        if not lo - 1e-12 <= orientation <= hi + 1e-12:
            raise ValueError(
                f"sensor orientation={orientation!r} out of range; allowed: [{lo:.6g}, {hi:.6g}]"
            )
        if spec.configurable:
            r_allowed = f"({spec.range_min:g}, {spec.range_max:g}] for {spec.name}"
            f_allowed = f"[{spec.fov_min:.6g}, {spec.fov_max:.6g}] for {spec.name}"
            if self.range is None:
                raise ValueError(f"sensor range is required; allowed: {r_allowed}")
            if self.fov is None:
                raise ValueError(f"sensor fov is required; allowed: {f_allowed}")
            rng = _number("range", self.range, r_allowed)
            fov = _number("fov", self.fov, f_allowed)
            if not spec.range_min < rng <= spec.range_max:
                raise ValueError(f"sensor range={rng!r} out of range; allowed: {r_allowed}")
            if not spec.fov_min - 1e-9 <= fov <= spec.fov_max + 1e-9:
                raise ValueError(f"sensor fov={fov!r} out of range; allowed: {f_allowed}")
            fov = min(max(fov, spec.fov_min), spec.fov_max)
        else:
            for name in ("range", "fov"):
                value = getattr(self, name)
                if value is not None and _number(name, value, "0 (fixed for bottom)") != 0.0:
                    raise ValueError(
                        f"sensor {name}={value!r} not allowed for a bottom sensor; allowed: 0 or None"
                    )
            rng, fov = 0.0, 0.0
        object.__setattr__(self, "bearing", bearing)
        object.__setattr__(self, "orientation", orientation)
        object.__setattr__(self, "range", rng)
        object.__setattr__(self, "fov", fov)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict: {'type', 'bearing', 'orientation', 'range', 'fov'}."""
        return {
            "type": self.type,
            "bearing": self.bearing,
            "orientation": self.orientation,
            "range": self.range,
            "fov": self.fov,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SensorSpec:
        """Inverse of ``to_dict``; unknown keys raise ``ValueError``."""
        if not isinstance(data, Mapping):
            raise ValueError(f"sensor must be a dict with key 'type'; got {data!r}")
        allowed = {"type", "bearing", "orientation", "range", "fov"}
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise ValueError(f"unknown sensor field(s) {unknown}; allowed: {sorted(allowed)}")
        if "type" not in data:
            raise ValueError(f"sensor field 'type' is missing; allowed: {list(SENSOR_TYPES)}")
        return cls(**dict(data))


class Morphology(Sequence[SensorSpec]):
    """An ordered, immutable sensor suite of at most ``MAX_SENSORS`` sensors.

    The observation of each robot has one entry per sensor, in this order.
    """

    __slots__ = ("_sensors",)

    def __init__(self, sensors: Iterable[SensorSpec | Mapping[str, Any]] = ()) -> None:
        items = []
        for i, s in enumerate(sensors):
            if isinstance(s, SensorSpec):
                items.append(s)
            else:
                try:
                    items.append(SensorSpec.from_dict(s))
                except ValueError as err:
                    raise ValueError(f"morphology sensor[{i}]: {err}") from None
        if len(items) > MAX_SENSORS:
            raise ValueError(
                f"morphology has {len(items)} sensors; allowed: at most {MAX_SENSORS}"
            )
        self._sensors: tuple[SensorSpec, ...] = tuple(items)

    # Sequence protocol
    def __len__(self) -> int:
        return len(self._sensors)

    def __getitem__(self, index):  # type: ignore[override]
        return self._sensors[index]

    def __iter__(self) -> Iterator[SensorSpec]:
        return iter(self._sensors)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Morphology) and self._sensors == other._sensors

    def __hash__(self) -> int:
        return hash(self._sensors)

    def __repr__(self) -> str:
        inner = ", ".join(f"{s.type}@{math.degrees(s.bearing):.0f}deg" for s in self._sensors)
        return f"Morphology([{inner}])"

    @property
    def sensors(self) -> tuple[SensorSpec, ...]:
        return self._sensors

    def count_by_type(self) -> dict[str, int]:
        """Number of sensors of each type (every type present as a key)."""
        counts = dict.fromkeys(SENSOR_TYPES, 0)
        for s in self._sensors:
            counts[s.type] += 1
        return counts

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe: {'sensors': [sensor dicts]}."""
        return {"sensors": [s.to_dict() for s in self._sensors]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | Sequence[Mapping[str, Any]]) -> Morphology:
        """Accepts ``{'sensors': [...]}`` (the ``to_dict`` form) or a plain list of sensor dicts."""
        if isinstance(data, Mapping):
            if set(data) != {"sensors"}:
                raise ValueError(
                    f"morphology dict must have exactly the key 'sensors'; got {sorted(data)}"
                )
            data = data["sensors"]
        if isinstance(data, (str, bytes)) or not isinstance(data, Sequence):
            raise ValueError(f"morphology must be a list of sensor dicts; got {type(data).__name__}")
        return cls(data)

    @classmethod
    def coerce(cls, value: Any) -> Morphology:
        """A ``Morphology`` from a Morphology, a list of SensorSpec/dicts or a dict."""
        if isinstance(value, Morphology):
            return value
        if isinstance(value, (Mapping, Sequence)) and not isinstance(value, (str, bytes)):
            return cls.from_dict(value) if isinstance(value, Mapping) else cls(value)
        raise ValueError(
            f"morphology must be a Morphology, a list of sensors or {{'sensors': [...]}}; "
            f"got {type(value).__name__}"
        )

    @classmethod
    def khepera_iii(cls) -> Morphology:
        """The default suite (docs/model.md §3): bottom; IR at +-40 deg; ultrasonic at 0, +-90 deg.

        IR: range 0.2 units, FOV pi/6 (the type minimum). Ultrasonic: range 4.0, FOV 1.22.
        """
        ir = dict(type="infrared", range=0.2, fov=math.pi / 6)
        us = dict(type="ultrasonic", range=4.0, fov=1.22)
        return cls([
            SensorSpec("bottom"),
            SensorSpec(bearing=math.radians(40), **ir),
            SensorSpec(bearing=math.radians(-40), **ir),
            SensorSpec(bearing=0.0, **us),
            SensorSpec(bearing=math.pi / 2, **us),
            SensorSpec(bearing=-math.pi / 2, **us),
        ])


BOTTOM_SENSOR_COST = 10.0
"""A bottom sensor subtracts a flat 10 from the complexity score (as in the original)."""


COMPLEXITY_FORMULAS: tuple[str, str] = ("paper", "original")
"""Versions of eq. 2 (``morphological_complexity(formula=...)``)."""


def morphological_complexity(morphology: Morphology | Iterable[SensorSpec | Mapping[str, Any]],
                             formula: str = "paper") -> float:
    """Paper eq. 2: ``C = 100 - 5 * sum_i [(f_i - minF)/(maxF - minF) + (r_i - minR)/(maxR - minR)]``.

    Bounds per type come from ``SENSOR_TYPES`` (minR = 0). A bottom sensor costs a flat 10.
    Higher C = simpler: 100 for no sensors, 0 for ten sensors at maximum range and FOV.

    ``formula = "original"``: eq. 2 as the original code computed it: the range term counted
    twice (``10 * (r_i - minR)/(maxR - minR)``), no FOV term, and an infrared sensor a flat 10
    like the bottom sensor (its class name fell through the type mapping).
    """
    if formula not in COMPLEXITY_FORMULAS:
        raise ValueError(f"formula={formula!r}; allowed: {', '.join(map(repr, COMPLEXITY_FORMULAS))}")
    morph = Morphology.coerce(morphology if isinstance(morphology, Morphology) else list(morphology))
    original = formula == "original"
    penalty = 0.0
    for s in morph:
        spec = SENSOR_TYPES[s.type]
        if not spec.configurable or (original and s.type == "infrared"):
            penalty += BOTTOM_SENSOR_COST
            continue
        range_term = (s.range - spec.range_min) / (spec.range_max - spec.range_min)
        if original:
            penalty += 5.0 * range_term + 5.0 * range_term
            continue
        fov_term = (s.fov - spec.fov_min) / (spec.fov_max - spec.fov_min)
        penalty += 5.0 * (fov_term + range_term)
    return 100.0 - penalty
