"""The re-evaluation cache is validated like a checkpoint: a damaged, edited, malformed or
other-version cache is reported in one line and set aside (renamed, never overwritten), and
nothing from it reaches a score or a report."""

from __future__ import annotations

import json
import math
import shutil

import pytest
import small_runs

from evolution.analysis import reevaluate as reevaluation
from evolution.analysis.reevaluate import CACHE_FILE, reevaluate_run
from evolution.cli import analyze_main

K = 2


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A copy of the shared SO run with a cache written by reevaluate_run, and its scores."""
    _, so, _, _ = small_runs.build(tmp_path_factory)
    root = tmp_path_factory.mktemp("cache-trust")
    shutil.copytree(so, root / "so")
    scores = reevaluate_run(root / "so", K, workers=1, backend="serial")
    return root / "so", scores


def forge(doc: dict, entry: dict, damage: str) -> None:
    """Damage a cache document in place, as a user, a disk or another version would."""
    if damage == "edited-999":
        entry["task"] = 999.0                        # checksum left as it was
    elif damage == "nan-with-fresh-checksum":
        entry["task"] = math.nan
        doc["checksum"] = reevaluation._checksum(doc["entries"])
    elif damage == "string-score-with-fresh-checksum":
        entry["task"] = "57.3"
        doc["checksum"] = reevaluation._checksum(doc["entries"])
    elif damage == "trial-ft-short":
        entry["trial_ft"] = entry["trial_ft"][:1]
        doc["checksum"] = reevaluation._checksum(doc["entries"])
    elif damage == "entries-a-list":
        doc["entries"] = [entry]
    elif damage == "other-version":
        doc["version"] = 1
    elif damage == "no-checksum":
        del doc["checksum"]


DAMAGES = ["edited-999", "nan-with-fresh-checksum", "string-score-with-fresh-checksum", "trial-ft-short",
           "entries-a-list", "other-version", "no-checksum"]


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_cache_is_set_aside_and_nothing_from_it_is_used(pristine, tmp_path, damage):
    run, scores = pristine
    copy = tmp_path / "so"
    shutil.copytree(run, copy)
    doc = json.loads((copy / CACHE_FILE).read_text())
    forge(doc, next(iter(doc["entries"].values())), damage)
    damaged = json.dumps(doc)  # allow_nan: the NaN case writes the literal NaN a forger would
    (copy / CACHE_FILE).write_text(damaged)
    with pytest.warns(UserWarning) as caught:
        again = reevaluate_run(copy, K, workers=1, backend="serial")
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1 and messages[0].startswith(f"{copy / CACHE_FILE}: ") and "set aside" in messages[0]
    assert again == scores                                       # recomputed, not read from the damaged file
    assert (copy / f"{CACHE_FILE}.set-aside-1").read_text() == damaged  # kept byte for byte
    assert reevaluate_run(copy, K, workers=1, backend="serial") == scores  # the new cache is trusted


def test_the_report_never_shows_a_tampered_score_and_a_second_copy_is_not_overwritten(pristine, tmp_path,
                                                                                     capsys):
    run, scores = pristine
    copy = tmp_path / "so"
    shutil.copytree(run, copy)
    (copy / f"{CACHE_FILE}.set-aside-1").write_text("an earlier set-aside copy\n")
    doc = json.loads((copy / CACHE_FILE).read_text())
    for entry in doc["entries"].values():
        entry["task"] = 999.0
    (copy / CACHE_FILE).write_text(json.dumps(doc))
    out = tmp_path / "report"
    assert analyze_main([str(copy), "--out", str(out), "--reevaluate", str(K), "--workers", "1"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len([line for line in err if line.startswith("warning: ")]) == 1
    assert "checksum mismatch" in err[0] and f"set aside as {CACHE_FILE}.set-aside-2" in err[0]
    assert (copy / f"{CACHE_FILE}.set-aside-1").read_text() == "an earlier set-aside copy\n"
    report = (out / "report.md").read_text()
    assert "999" not in report + (out / "table4.csv").read_text()
    assert f"AVG SO = ({scores['champion.json']['task']:.2f}, " in report  # the recomputed held-out score
