"""The original's Khepera III proximity curve (its ``ProximitySensor`` and ``BottomProximitySensor``).

The 2018 simulator models the Khepera's infrared proximity sensor (a Vishay TCRT5000) by the
density of a Gamma distribution (shape 2.5, scale 2) over the distance in millimetres, scaled by
6.64 and capped at 1. A sensor of range R first rescales its distance d to the datasheet's range
of 0.2, so the density is read at ``x = 1000 * 0.2 * d / R``: the reading is 0 at contact, 1 for
x in [2.51, 3.56] (d = 1.3-1.8 % of R), below 0.1 from x = 11.7 (d = 5.9 % of R) and below 0.01
from x = 17.6 (8.8 % of R): a near-contact sensor, whatever its range.

The bottom sensor is the same curve on a disc of radius 0.05 placed 0.95 robot radii ahead of the
robot's centre, at range 0.2, read 2.5 mm above the ground: over the zone it reads the curve at
x = 2.5 (0.99999...), outside it the curve at ``1000 (d + 0.0025)`` with d the distance from the
disc's centre to the zone along x (or along y when the disc lies beside the zone in x), while the
disc still overlaps the zone (Euclidean distance < 0.05), else 0: an on/off reading at the
robot's front.

``ir_response = "khepera"`` and ``bottom_response = "khepera"`` select these
(``gathering_env.config.WorldConfig``); both kernels read the constants below.
"""

from __future__ import annotations

import math

import numpy as np

SHAPE = 2.5
SCALE = 2.0
GAIN = 6.64
#: 1 / (Gamma(shape) scale^shape): the density's normalising constant.
NORM = 1.0 / (math.gamma(SHAPE) * SCALE ** SHAPE)
#: Distances are normalised to this range and read in millimetres: x = MM * REFERENCE_RANGE * d / R.
REFERENCE_RANGE = 0.2
MM = 1000.0
#: The bottom sensor: a disc of this radius, this many robot radii ahead of the centre, read this
#: high above the ground.
BOTTOM_RADIUS = 0.05
BOTTOM_AHEAD = 0.95
BOTTOM_HEIGHT = 0.0025


def curve(x):
    """min(GAIN * density(x), 1) of the Gamma(2.5, scale 2) density at x >= 0 (arrays or floats)."""
    x = np.asarray(x, dtype=float)
    return np.minimum(GAIN * NORM * x ** (SHAPE - 1.0) * np.exp(-x / SCALE), 1.0)


__all__ = ["curve", "SHAPE", "SCALE", "GAIN", "NORM", "REFERENCE_RANGE", "MM", "BOTTOM_RADIUS",
           "BOTTOM_AHEAD", "BOTTOM_HEIGHT"]
