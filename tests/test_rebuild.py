"""Rebuilding a run from its record (``--rebuild-from``): the recorded generations take the
recorded scores without a step simulated, the lineage and statistics are the unbroken
run's, and a record that does not match the run stops it naming what differs."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from small_runs import comparable_stats, evolve, experiment_file

from evolution.cli import evolve_main
from evolution.run import evaluate as evaluate_module
from evolution.run.rebuild import RebuildError, load_record
from evolution.run.stats import WORK_KEYS, read_stats

CASES = {
    "hyperneat-so": ("hyperneat-m", '["task"]', ""),
    "neat-m-mo": ("neat-m", '["task", "morphology"]', ""),
    "ratchet-per-run": ("hyperneat-m", '["task"]', 'layout = "per_run"\nelitism = "ratchet"\nspeciation = "original"'),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def runs(request, tmp_path_factory):
    """(experiment, 5-generation run, its 3-generation record) of one case."""
    root = tmp_path_factory.mktemp(request.param)
    method, objectives, extra = CASES[request.param]
    exp = experiment_file(root, request.param, method, objectives, generations=5, extra=extra)
    evolve(exp, root / "whole")
    evolve(exp, root / "record", "--generations", "3")
    return exp, root / "whole", root / "record"


def test_the_record_holds_scores_that_differ(runs):
    """The test data can tell genomes apart: a rebuild that mixed up scores would breed otherwise."""
    _, whole, _ = runs
    recorded = read_stats(whole / "stats.jsonl")[:3]
    assert any(len({tuple(f) for f in r["trial_ft"].values()}) >= 2 for r in recorded)


def test_a_rebuilt_run_is_the_unbroken_run_without_simulating_the_record(runs, tmp_path, monkeypatch):
    exp, whole, record = runs
    real = evaluate_module.evaluate

    def no_recorded_generation(genome, config, env_config, *args, generation=0, **kwargs):
        assert generation >= 3, f"generation {generation} is recorded and was simulated"
        return real(genome, config, env_config, *args, generation=generation, **kwargs)

    monkeypatch.setattr(evaluate_module, "evaluate", no_recorded_generation)
    monkeypatch.setattr("evolution.run.backends.evaluate", no_recorded_generation)
    evolve(exp, tmp_path / "rebuilt", "--rebuild-from", str(record))
    assert comparable_stats(tmp_path / "rebuilt") == comparable_stats(whole)
    assert (tmp_path / "rebuilt" / "champion.json").read_bytes() == (whole / "champion.json").read_bytes()
    rebuilt, recorded = read_stats(tmp_path / "rebuilt" / "stats.jsonl"), read_stats(record / "stats.jsonl")
    for new, old in zip(rebuilt[:3], recorded):  # the recorded run's work, not the rebuild's
        assert {k: new[k] for k in WORK_KEYS} == {k: old[k] for k in WORK_KEYS}
    if (whole / "front").is_dir():
        assert sorted(p.name for p in (tmp_path / "rebuilt" / "front").iterdir()) == \
            sorted(p.name for p in (whole / "front").iterdir())


def test_the_experiment_comes_from_the_record_when_none_is_given(runs, tmp_path):
    _, whole, record = runs
    assert evolve_main(["--rebuild-from", str(record), "--generations", "5", "--out", str(tmp_path / "r"),
                        "--workers", "1", "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "r") == comparable_stats(whole)


def _tampered(record: Path, tmp_path: Path, change) -> Path:
    copy = tmp_path / "tampered"
    shutil.copytree(record, copy)
    records = read_stats(copy / "stats.jsonl")
    change(records)
    (copy / "stats.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return copy


def _refused(exp: Path, source: Path, out: Path, capsys) -> str:
    assert evolve_main([str(exp), "--out", str(out), "--rebuild-from", str(source), "--workers", "1",
                        "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_a_changed_score_stops_the_run_at_its_generation(runs, tmp_path, capsys):
    exp, _, record = runs

    def change(records):
        key = sorted(records[1]["trial_ft"], key=int)[0]
        records[1]["trial_ft"][key] = [f + 7.5 for f in records[1]["trial_ft"][key]]

    line = _refused(exp, _tampered(record, tmp_path, change), tmp_path / "out", capsys)
    assert "generation 1: " in line and "rebuilt" in line and "the run stopped" in line


def test_a_record_of_other_genomes_is_refused(runs, tmp_path, capsys):
    exp, _, record = runs

    def change(records):
        scores = records[2]["trial_ft"]
        key = sorted(scores, key=int)[-1]
        scores[str(int(key) + 1000)] = scores.pop(key)

    line = _refused(exp, _tampered(record, tmp_path, change), tmp_path / "out", capsys)
    assert "generation 2 scored other genomes" in line


def test_a_record_of_another_experiment_is_refused(runs, tmp_path, capsys):
    exp, _, record = runs
    copy = tmp_path / "other-seed"
    shutil.copytree(record, copy)
    saved = json.loads((copy / "experiment.json").read_text())
    saved["seed"] = 4
    (copy / "experiment.json").write_text(json.dumps(saved))
    line = _refused(exp, copy, tmp_path / "out", capsys)
    assert "'seed' is 4, the new run's is 3" in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("case", ["no scores", "bad score", "too many generations", "no experiment", "missing",
                                  "empty"])
def test_bad_records_get_one_line_and_nothing_is_written(runs, tmp_path, case):
    exp, _, record = runs
    copy = tmp_path / "bad"
    shutil.copytree(record, copy)
    records = read_stats(copy / "stats.jsonl")
    expect = {"no scores": "has no per-genome scores", "bad score": "allowed: a genome id with a list",
              "too many generations": "more than the new run's 2", "no experiment": "experiment.json: missing",
              "missing": "no stats.jsonl there", "empty": "records no generation"}[case]
    if case == "empty":
        records = []
    if case == "no scores":
        del records[0]["trial_ft"]
    if case == "bad score":
        records[1]["trial_ft"][next(iter(records[1]["trial_ft"]))] = ["NaN?"]
    (copy / "stats.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    if case == "no experiment":
        (copy / "experiment.json").unlink()
    if case == "missing":
        (copy / "stats.jsonl").unlink()
    saved = json.loads((record / "experiment.json").read_text())
    with pytest.raises(RebuildError, match=expect):
        load_record(copy, {**saved, "generations": 2 if case == "too many generations" else 5})


def test_a_missing_record_without_an_experiment_is_one_line(tmp_path, capsys):
    assert evolve_main(["--rebuild-from", str(tmp_path / "nope"), "--out", str(tmp_path / "out"),
                        "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope: no stats.jsonl there" in err[0]
    assert not (tmp_path / "out").exists()


def test_rebuild_and_resume_do_not_mix(runs, tmp_path, capsys):
    exp, whole, record = runs
    shutil.copytree(whole, tmp_path / "run")
    assert evolve_main(["--resume", str(tmp_path / "run"), "--rebuild-from", str(record), "--no-progress"]) == 2
    assert "--rebuild-from" in capsys.readouterr().err


def test_a_rebuild_into_the_record_itself_is_refused_and_changes_nothing(runs, tmp_path, capsys):
    exp, _, record = runs
    copy = tmp_path / "record"
    shutil.copytree(record, copy)
    before = {p.name: p.read_bytes() for p in copy.rglob("*") if p.is_file()}
    line = _refused(exp, copy, copy, capsys)
    assert "choose another --out" in line or "continue it with" in line
    assert {p.name: p.read_bytes() for p in copy.rglob("*") if p.is_file()} == before


COMMITTED = Path(__file__).parents[1] / "docs" / "evidence" / "original-S1-continued"


def test_the_committed_record_rebuilds_with_this_code(tmp_path):
    """The S1-original run continued across sessions (docs/evidence/original-S1-continued) is
    rebuilt from its record: its first generations, bred, decoded and speciated by this code, ask
    for the recorded genomes and give the recorded statistics. A change to breeding, speciation
    or decoding that would alter that run fails here, before a session spends hours on it."""
    keep = 5
    copy = tmp_path / "record"
    copy.mkdir()
    shutil.copy(COMMITTED / "experiment.json", copy)
    lines = (COMMITTED / "stats.jsonl").read_text().splitlines()[:keep]
    (copy / "stats.jsonl").write_text("\n".join(lines) + "\n")
    assert evolve_main(["--rebuild-from", str(copy), "--generations", str(keep), "--out", str(tmp_path / "r"),
                        "--workers", "1", "--no-progress"]) == 0
    assert comparable_stats(tmp_path / "r") == comparable_stats(copy)
