"""Morphological complexity (paper eq. 2) by hand, and JSON round trips."""

from __future__ import annotations

import json
import math

import pytest

from gathering_env import SENSOR_TYPES, Morphology, SensorSpec, morphological_complexity


def test_empty_and_full_morphologies():
    assert morphological_complexity(Morphology()) == 100.0
    full = [SensorSpec(t, range=SENSOR_TYPES[t].range_max, fov=SENSOR_TYPES[t].fov_max)
            for t in ("infrared", "ultrasonic", "colour", "camera", "camera") * 2]
    assert morphological_complexity(full) == pytest.approx(0.0)   # 10 x 5 x (1 + 1)


def test_khepera_iii_by_hand():
    # bottom: flat 10. IR: fov at the minimum (0), range 0.2/10 -> 5 * 0.02 = 0.1 each.
    # Ultrasonic: fov (1.22 - 0.1) / (pi - 0.1), range 4/25 -> 5 * (0.36822 + 0.16) each.
    us = 5 * ((1.22 - 0.1) / (math.pi - 0.1) + 4.0 / 25.0)
    expected = 100 - 10 - 2 * 0.1 - 3 * us
    assert morphological_complexity(Morphology.khepera_iii()) == pytest.approx(expected)
    assert expected == pytest.approx(81.876, abs=1e-3)


def test_one_camera_by_hand():
    cam = SensorSpec("camera", range=10.0, fov=(math.pi / 9 + 8 * math.pi / 9) / 2)  # half range, mid fov
    assert morphological_complexity([cam]) == pytest.approx(100 - 5 * (0.5 + 0.5))


def test_json_round_trip():
    morph = Morphology.khepera_iii()
    text = json.dumps(morph.to_dict())
    again = Morphology.from_dict(json.loads(text))
    assert again == morph and hash(again) == hash(morph)
    assert Morphology.from_dict(json.loads(text)["sensors"]) == morph   # plain list form
    assert SensorSpec.from_dict(morph[1].to_dict()) == morph[1]
    assert morph.count_by_type() == {"infrared": 2, "ultrasonic": 3, "colour": 0, "camera": 0, "bottom": 1}
