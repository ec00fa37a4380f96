"""Every picture of docs/ is made by examples/docs_images.py (make docs-images), so none can go
stale unnoticed: the script's list of outputs and the pictures in docs/ are the same set.
Checked without running the script (its steps take minutes to hours)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(name, module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_every_picture_in_docs_is_made_by_the_script_and_nothing_else():
    images = load("docs_images")
    in_docs = images.pictures_in_docs()
    made = images.outputs()
    assert sorted(in_docs - made) == [], "pictures in docs/ that no step of docs_images.py makes"
    assert sorted(made - in_docs) == [], "outputs of docs_images.py missing from docs/"


def test_the_gallery_step_lists_what_render_gallery_draws():
    assert load("docs_images").GALLERY == load("render_gallery").NAMES


def test_pictures_in_docs_finds_nested_pictures(tmp_path):
    (tmp_path / "a" / "b").mkdir(parents=True)
    for name in ("x.png", "a/y.gif", "a/b/z.PNG", "a/notes.md"):
        (tmp_path / name).write_text("")
    assert load("docs_images").pictures_in_docs(tmp_path) == {"x.png", "a/y.gif", "a/b/z.PNG"}


def test_original_runs_without_the_two_runs_is_refused_before_any_step(tmp_path, capsys):
    (tmp_path / "M1-original").mkdir()
    (tmp_path / "M1-original" / "stats.jsonl").write_text("")
    assert load("docs_images").main(["--only", "original-m1-analysis", "--original-runs", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "no S1-original-continued/stats.jsonl" in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["M1-original"]


def test_original_runs_checks_the_runs_of_the_step_chosen(tmp_path, capsys):
    # version 2's runs are present, version 3's S1 is not: only the version-3 step is refused
    for name in ("S1-original-continued", "M1-original", "M1-original-five"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "stats.jsonl").write_text("")
    assert load("docs_images").main(["--only", "original-m1-five-analysis", "--original-runs", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "no S1-original-five/stats.jsonl" in err and "original-m1-five-analysis" in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["M1-original", "M1-original-five", "S1-original-continued"]


def test_original_runs_does_not_ask_for_the_runs_of_a_step_not_chosen(tmp_path):
    # only version 2's runs: its step runs (its make replaced by a recorder), version 3's are not asked for
    for name in ("S1-original-continued", "M1-original"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "stats.jsonl").write_text("")
    module = load("docs_images")
    made = []
    module.STEPS["original-m1-analysis"] = module.Step((), "original_runs", made.append)
    assert module.main(["--only", "original-m1-analysis", "--original-runs", str(tmp_path)]) == 0
    assert [args.original_runs for args in made] == [tmp_path]


def test_an_only_that_names_no_step_is_refused_and_runs_nothing(capsys):
    module = load("docs_images")
    made = []
    for name in list(module.STEPS):
        module.STEPS[name] = module.Step((), None, made.append)
    for only in (",", " , ", ""):
        try:
            module.main(["--only", only])
        except SystemExit as stop:
            assert stop.code == 2
        else:
            raise AssertionError(f"--only {only!r} was accepted")
        assert "names no step" in capsys.readouterr().err
    assert made == []


def test_a_champion_that_is_not_a_file_is_refused_before_any_step(tmp_path, capsys):
    module = load("docs_images")
    made = []
    module.STEPS["gallery"] = module.Step((), None, made.append)
    for champion in (tmp_path / "missing.json", tmp_path):
        try:
            module.main(["--only", "gallery", "--champion", str(champion)])
        except SystemExit as stop:
            assert stop.code == 2
        else:
            raise AssertionError(f"--champion {champion} was accepted")
        err = capsys.readouterr().err
        assert "--champion" in err and "no such file" in err
    assert made == [] and list(tmp_path.iterdir()) == []
