"""examples/weight_steps.py: what share of weight mutations change the decoded phenotype.

Hand-built CPPNs (no links, every output's value its node bias, clipped to [-1, 1]) whose
saturation is known: a bias at the bound 3 gives an output of 1 that no perturbation of
N(0, 0.5) clamped to [-3, 3] moves below 1 unless it falls by more than 2 (p < 1e-4), so only
the 1-in-10 resets of the shipped config can change it. Each genome has six biases; a
mutation touches 1, 2, 3 of them or 2 % (one)."""

from __future__ import annotations

import contextlib
import importlib.util
from pathlib import Path

import pytest
import small_runs
from test_substrate import BIAS, FOV, ORIENT, RANGE, TYPE, WEIGHT, cppn, cppn_config

from evolution.encodings.substrate import Substrate

ROOT = Path(__file__).resolve().parent.parent
SATURATED = {WEIGHT: 3.0, FOV: 3.0, ORIENT: 3.0, RANGE: 3.0, TYPE: 3.0, BIAS: 3.0}


def load():
    spec = importlib.util.spec_from_file_location("weight_steps", ROOT / "examples" / "weight_steps.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def steps():
    return load()


@pytest.fixture(scope="module")
def config():
    return cppn_config()


def figures(steps, config, biases, mutations=200):
    genome = cppn(config, {}, biases)
    return steps.weight_steps("hyperneat-m", [genome], config, Substrate(), mutations, seed=3)


def test_a_saturated_cppn_is_mostly_unchanged_and_all_its_links_at_the_bound(steps, config):
    f = figures(steps, config, SATURATED)
    assert f["links at the bound"] == 1.0            # every weight and bias decodes to +5
    assert f["unchanged"] > 0.85                      # only resets (10 %) can change it
    assert f["types changed"] < 0.1


def test_an_open_weight_output_changes_the_controller_and_nothing_else(steps, config):
    # The weight output at 0.6 (linked, not clipped): a step on its bias moves every link by
    # 6.25 times the step; the other outputs stay clipped. Ignoring the controller in the
    # comparison would leave nearly all of these mutations "unchanged".
    f = figures(steps, config, {**SATURATED, WEIGHT: 0.6})
    assert f["links at the bound"] == pytest.approx(2 / 22)   # 20 links at 2.5, 2 biases at 5
    assert 0.4 < f["unchanged"] < 0.85
    assert f["median step"] > 0.5


def test_an_open_fov_output_changes_the_morphology(steps, config):
    # Only the FOV output is open: a change shows in the sensors alone. Ignoring the morphology
    # in the comparison would leave nearly all of these mutations "unchanged".
    f = figures(steps, config, {**SATURATED, FOV: 0.0})
    assert 0.4 < f["unchanged"] < 0.85
    assert f["types changed"] < 0.1


def test_nothing_open_nothing_unchanged(steps, config):
    # Every output open (type mid-band in camera): nearly every mutation shows.
    f = figures(steps, config, {WEIGHT: 0.6, FOV: 0.0, ORIENT: 0.0, RANGE: 0.0, TYPE: 0.25, BIAS: 0.1})
    assert f["unchanged"] < 0.2 and f["links at the bound"] == 0.0


def test_the_script_reads_a_run_and_refuses_bad_input(steps, tmp_path_factory, tmp_path, capsys):
    _, so_run, _, mo_run = small_runs.build(tmp_path_factory)
    assert steps.main([str(so_run), str(mo_run), "--mutations", "2"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| so") or line.startswith("| mo")]
    assert len(rows) == 4 and "generation" in rows[0] and "fresh" in rows[1]
    assert rows[2].split("|")[6].strip() == "–"       # NEAT-M: no substrate bound
    (tmp_path / "empty").mkdir()
    for args, needle in (([str(so_run), str(tmp_path / "nope")], "run folder not found"),
                         ([str(tmp_path / "empty")], "no checkpoint to resume from"),
                         ([str(so_run), "--mutations", "0"], "--mutations: 0 is out of range")):
        with pytest.raises(SystemExit) if "--mutations" in args else contextlib.nullcontext():
            assert steps.main(args) == 2
        out, err = capsys.readouterr()
        assert out == "" and needle in err and len(err.strip().splitlines()) == 1

