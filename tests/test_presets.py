"""Presets shipped in the package: names, --list, --dump, neat_config resolution, the version.

The installed-wheel round trip (build, install into a fresh virtualenv, run from outside the
repository) is the slow test in test_install.py.
"""

import json
import re
import tomllib
from pathlib import Path

import pytest

import gathering_env
from evolution import __version__ as evolution_version
from evolution.cli import evolve_main
from evolution.run.experiment import ExperimentError, load_experiment
from evolution.run.presets import (
    CONFIG_DIR,
    is_preset_name,
    preset_description,
    preset_names,
    preset_path,
)

ROOT = Path(__file__).resolve().parent.parent
PAPER_PRESETS = {"S1", "S2", "S3", "M1", "M2", "M3", "quick"}


def test_presets_are_the_repository_configs_folder():
    assert CONFIG_DIR == ROOT / "configs"
    assert set(preset_names()) == PAPER_PRESETS
    assert preset_path("S2") == ROOT / "configs" / "S2.toml"
    assert preset_path("hyperneat_m.neat.cfg", neat_configs=True) == ROOT / "configs" / "hyperneat_m.neat.cfg"


def test_list_prints_every_preset_with_its_first_comment_sentence(capsys):
    assert evolve_main(["--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    listed = {line.split()[0]: line.split(None, 1)[1] for line in lines if not line.startswith("#")}
    original = {f"{name}-original" for name in ("S1", "S2", "S3", "M1", "M2", "M3")}
    assert set(listed) == PAPER_PRESETS | original | {"hyperneat_m.neat.cfg", "neat_m.neat.cfg"}
    # one header line per set: the paper's presets, the original protocol's, the neat configs
    assert [line.split(":")[0] for line in lines if line.startswith("#")] == [
        '# protocol "paper"', '# protocol "original" (version 11; protocol_version picks another)', "# neat-python configs"]
    # hand-read from the files' opening comments
    assert listed["S1"] == "Experiment S1 of the paper: single objective (task performance), environment 1."
    assert listed["M3"].startswith("Experiment M3 of the paper: multi-objective")
    # a sentence that continues on the next comment line is joined
    assert listed["neat_m.neat.cfg"].endswith("plus sensor genes), docs/model.md §5.")
    assert preset_description("quick") == listed["quick"]


def test_dump_writes_the_preset_file_verbatim(capsys):
    assert evolve_main(["--dump", "S1"]) == 0
    assert capsys.readouterr().out == (ROOT / "configs" / "S1.toml").read_text(encoding="utf-8")
    assert evolve_main(["--dump", "neat_m.neat.cfg"]) == 0
    assert capsys.readouterr().out == (ROOT / "configs" / "neat_m.neat.cfg").read_text(encoding="utf-8")


def test_dumped_preset_resolves_its_neat_config_anywhere(tmp_path, capsys):
    assert evolve_main(["--dump", "M2"]) == 0
    mine = tmp_path / "my.toml"
    mine.write_text(capsys.readouterr().out, encoding="utf-8")
    experiment = load_experiment(mine)
    assert experiment.neat_config == ROOT / "configs" / "hyperneat_m.neat.cfg"
    assert experiment.objectives == ("task", "morphology") and experiment.environment["environment"] == 2
    # the rule: a neat config next to the experiment file wins over the shipped one
    local = tmp_path / "hyperneat_m.neat.cfg"
    local.write_text((ROOT / "configs" / "hyperneat_m.neat.cfg").read_text(encoding="utf-8"), encoding="utf-8")
    assert load_experiment(mine).neat_config == local


def test_unknown_preset_is_one_line_listing_the_known_ones(capsys):
    assert evolve_main(["S9"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: S9: unknown preset")
    for name in PAPER_PRESETS:
        assert re.search(rf"\b{name}\b", err)
    assert evolve_main(["--dump", "S9"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: --dump S9: unknown preset")
    assert "hyperneat_m.neat.cfg" in err
    with pytest.raises(ExperimentError, match="unknown preset"):
        preset_path("hyperneat_m.neat.cfg")  # a neat config is not an experiment


def test_a_path_is_still_a_path(tmp_path, monkeypatch, capsys):
    assert is_preset_name("S1") and is_preset_name("quick")
    assert not is_preset_name("configs/S1.toml") and not is_preset_name("S1.toml")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "S1").write_text('[experiment]\nname = "mine"\n', encoding="utf-8")
    assert not is_preset_name("S1")  # an existing file wins over the preset name
    assert load_experiment("S1").name == "mine"
    assert evolve_main(["missing.toml"]) == 2
    assert "missing.toml: experiment file not found" in capsys.readouterr().err


def test_evolve_runs_a_preset_by_name(tmp_path, capsys):
    out = tmp_path / "run"
    code = evolve_main(["quick", "--generations", "1", "--population", "4", "--steps", "100",
                        "--workers", "1", "--no-progress", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    record = json.loads((out / "experiment.json").read_text(encoding="utf-8"))
    quick = tomllib.loads((ROOT / "configs" / "quick.toml").read_text(encoding="utf-8"))
    assert record["name"] == "quick" and record["trials"] == quick["experiment"]["trials"]
    assert record["environment"]["environment"] == quick["environment"]["environment"]
    assert (out / "neat.cfg").read_bytes() == (ROOT / "configs" / "hyperneat_m.neat.cfg").read_bytes()


def test_one_version(capsys):
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" in pyproject["project"]["dynamic"] and "version" not in pyproject["project"]
    assert pyproject["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "gathering_env.__version__"}
    assert re.fullmatch(r"\d+\.\d+\.\d+([ab]\d+|rc\d+)?(\.dev\d+)?", gathering_env.__version__)
    assert evolution_version == gathering_env.__version__
    with pytest.raises(SystemExit):
        evolve_main(["--version"])
    assert capsys.readouterr().out.strip() == f"gathering-evolve {gathering_env.__version__}"


def test_citation_names_the_paper():
    yaml = pytest.importorskip("yaml")
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert citation["cff-version"] == "1.2.0" and citation["type"] == "software"
    paper = citation["preferred-citation"]
    assert paper["title"] == ("The Impact of Imposing a Cost on Morphological Complexity for Teams of "
                              "Cooperating Robots")
    assert paper["authors"][0]["family-names"] == "Nagar"
    assert "version" not in citation  # the version lives in gathering_env.__version__ only


class _Parsed(Exception):
    def __init__(self, parser):
        self.parser = parser


@pytest.mark.parametrize("main", ["evolution.cli:evolve_main", "evolution.cli:replay_main",
                                  "evolution.cli:analyze_main", "evolution.compare:compare_main"])
def test_every_command_line_option_has_help_text(main, monkeypatch):
    import argparse
    import importlib

    module, name = main.split(":")

    def capture(self, *args, **kwargs):
        raise _Parsed(self)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", capture)
    with pytest.raises(_Parsed) as caught:
        getattr(importlib.import_module(module), name)([])
    bare = [a.option_strings[0] for a in caught.value.parser._actions if a.option_strings and not a.help]
    assert bare == []
