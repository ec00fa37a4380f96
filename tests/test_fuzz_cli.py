"""Property-based fuzzing of every CLI (hypothesis), in-process.

Mutated experiment TOMLs, neat configs, champion JSONs, checkpoints, statistics files and
command lines are fed to gathering-evolve, -replay, -analyze and -compare. Whatever the
input, a command must

* end with exit status 0 or 2 (argparse's own errors included),
* print no traceback,
* change no file outside the output it was asked to write, and
* change nothing inside an existing run directory unless it is resuming that run.

Each example gets a fresh copy of a small finished run. Values are drawn from pools of
invalid, odd and *small* valid values (so a valid input finishes in well under a second);
command lines always start with small-budget options that the drawn options may override.
The fast suite runs a modest, reproducible number of examples; ``-m slow`` runs many more.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import io
import json
import os
import shutil
import tempfile
import time
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, seed, settings
from hypothesis import strategies as st

from evolution.analysis.reevaluate import CACHE_FILE as REEVALUATION_CACHE
from evolution.cli import analyze_main, evolve_main, replay_main
from evolution.compare import compare_main

ROOT = Path(__file__).resolve().parent.parent
TINY = """[experiment]
name = "fz"
generations = 2
population = 4
trials = 1
seed = 3

[environment]
environment = 1
max_cycles = 20
num_robots = 3
arena_width = 10.0
arena_height = 10.0
zone_width = 6.0
zone_depth = 2.0
"""

TOML_VALUES = ["-1", "0", "1", "2", "3", "1.5", "nan", "inf", "true", '"x"', '""', "[]", "[1, 2]", "[0, 0, 0]",
               "[1, 1, 1]", "[3000, 0, 0]", "{}", "10000000000000", '"neat-m"', '"hyperneat-m"',
               '["task", "morphology"]', '["morphology"]', '"fz.cfg"', '"/"']
TOML_KEYS = ["name", "method", "objectives", "seed", "generations", "population", "trials", "convergence_stop",
             "neat_config", "environment", "max_cycles", "num_robots", "block_counts", "block_sizes", "dt",
             "zone_width", "arena_width", "robot_radius", "bottom_on_node0", "unknown_key"]
CFG_VALUES = ["-1", "0", "1", "2", "0.5", "nan", "inf", "1e9", "abc", "", "True", "full", "partial_direct 2",
              "sigmoid", "max", "none"]
JSON_VALUES = [None, -1, 0, 1, 2.5, 1e300, float("nan"), "x", "", [], {}, True, [1, 2], {"task": 1},
               {"sensors": []}, {"environment": 9}, [[1.0, 2.0]]]
ARG_VALUES = ["-1", "0", "1", "2", "3", "x", "", "1e3", "99999999999", "task", "task,morphology", ",",
              "serial", "process", "neat-m", "hyperneat-m", "random", "heuristic"]

FAST = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


# ---------------------------------------------------------------------------- the harness
@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """A folder with the experiment, a copy of the neat config and a finished 2-generation run."""
    root = tmp_path_factory.mktemp("fuzzbase")
    (root / "fz.toml").write_text(TINY)
    shutil.copy(ROOT / "configs" / "hyperneat_m.neat.cfg", root / "fz.cfg")
    assert evolve_main([str(root / "fz.toml"), "--out", str(root / "run"), "--workers", "1", "--no-progress"]) == 0
    return root


def snapshot(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


@contextlib.contextmanager
def workspace(base: Path):
    """A fresh copy of ``base`` plus an empty folder, a partial run folder and a plain file."""
    with tempfile.TemporaryDirectory(prefix="fuzz-") as tmp:
        work = Path(tmp)
        for item in base.iterdir():
            (shutil.copytree if item.is_dir() else shutil.copy)(item, work / item.name)
        (work / "empty").mkdir()
        (work / "partial").mkdir()
        shutil.copy(work / "run" / "champion.json", work / "partial" / "champion.json")
        (work / "afile").write_text("a user's file\n")
        cwd = os.getcwd()
        os.chdir(work)  # default output paths (runs/, team.gif, report/, compare/) land here
        try:
            yield work
        finally:
            os.chdir(cwd)


def run_cli(main, args: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(args)
        except SystemExit as stop:  # argparse errors and --help
            code = stop.code
    if os.environ.get("FUZZ_TRACE"):
        print(f"{time.perf_counter() - start:6.2f}s {code} {main.__name__} {args} {err.getvalue()[:150]!r}")
    return code, err.getvalue()


def check(work: Path, before: dict[str, str], code: int, err: str, writable: list[str]) -> None:
    """The four promises of the module docstring; ``writable``: folders/files it may change."""
    assert code in (0, 2), f"exit status {code}\n{err}"
    assert "Traceback" not in err, err
    if code == 2:
        assert "error: " in err, err
    after = snapshot(work)
    changed = sorted(p for p in set(before) | set(after) if before.get(p) != after.get(p))
    existed = {p.split("/")[0] for p in before}  # brand-new entries are the outputs the options named
    outside = [p for p in changed if p.split("/")[0] in existed
               and not any(p == w or p.startswith(w + "/") for w in writable)]
    assert not outside, f"changed outside the named output: {outside}\n{err}"


def new_outputs(work: Path) -> list[str]:
    """Existing entries a command may write into: the empty folder (a missing or empty output)."""
    return ["empty"]


def mutate_lines(data, text: str, values: list[str], keys: list[str]) -> str:
    lines = text.splitlines()
    for _ in range(data.draw(st.integers(1, 3), label="edits")):
        kind = data.draw(st.sampled_from(["replace", "delete", "insert", "truncate", "garbage"]), label="edit")
        i = data.draw(st.integers(0, max(len(lines) - 1, 0)), label="line")
        if kind == "replace" and lines and "=" in lines[i]:
            lines[i] = lines[i].split("=")[0] + "= " + data.draw(st.sampled_from(values), label="value")
        elif kind == "delete" and lines:
            del lines[i]
        elif kind == "insert":
            key = data.draw(st.sampled_from(keys), label="key")
            lines.insert(i, f"{key} = {data.draw(st.sampled_from(values), label='value')}")
        elif kind == "truncate":
            joined = "\n".join(lines)
            lines = joined[: data.draw(st.integers(0, len(joined)), label="cut")].splitlines()
        else:
            lines.insert(i, data.draw(st.sampled_from(["[", "[experiment]", "[environment]", "[substrate]",
                                                       "]]", "= 3", "\x00", "key ="]), label="garbage"))
    return "\n".join(lines) + "\n"


def mutate_json(data, doc):
    for _ in range(data.draw(st.integers(1, 3), label="edits")):
        target = doc
        if isinstance(doc, dict) and doc and data.draw(st.booleans(), label="nested"):
            key = data.draw(st.sampled_from(sorted(doc)), label="outer")
            if isinstance(doc[key], dict) and doc[key]:
                target = doc[key]
        if not isinstance(target, dict) or not target:
            return copy.deepcopy(data.draw(st.sampled_from(JSON_VALUES), label="whole"))
        key = data.draw(st.sampled_from(sorted(target)), label="key")
        if data.draw(st.booleans(), label="delete"):
            del target[key]
        else:
            target[key] = copy.deepcopy(data.draw(st.sampled_from(JSON_VALUES), label="value"))  # pool intact
    return doc


def draw_args(data, options: list[str], paths: list[str]) -> list[str]:
    args: list[str] = []
    for _ in range(data.draw(st.integers(0, 4), label="options")):
        option = data.draw(st.sampled_from(options), label="option")
        if option.startswith("--no-"):
            args.append(option)
        else:
            args += [option, data.draw(st.sampled_from(ARG_VALUES + paths), label=option)]
    return args


# ---------------------------------------------------------------------------- properties
def budget(text: str) -> list[str]:
    """Small-budget overrides for the keys a mutated TOML leaves to the (paper-sized) defaults."""
    try:
        section = tomllib.loads(text).get("experiment", {})
    except (tomllib.TOMLDecodeError, UnicodeDecodeError):
        return []
    if not isinstance(section, dict):
        return []
    small = {"generations": "1", "population": "2", "trials": "1"}
    return [arg for key, value in small.items() if key not in section for arg in (f"--{key}", value)]


def prop_experiment_file(base, data) -> None:
    with workspace(base) as work:
        text = mutate_lines(data, TINY, TOML_VALUES, TOML_KEYS)
        (work / "fz.toml").write_text(text)
        before = snapshot(work)
        out = data.draw(st.sampled_from(["new", "empty", "partial", "run", "afile"]), label="out")
        code, err = run_cli(evolve_main, ["fz.toml", "--out", out, "--steps", "20", "--workers", "1",
                                          "--no-progress", *budget(text)])
        check(work, before, code, err, new_outputs(work))


def prop_neat_config(base, data) -> None:
    with workspace(base) as work:
        text = (work / "fz.cfg").read_text()
        (work / "fz.cfg").write_text(mutate_lines(data, text, CFG_VALUES, ["num_hidden", "conn_add_prob",
                                                                           "weight_mutate_rate", "elitism",
                                                                           "compatibility_threshold", "bogus"]))
        (work / "fz.toml").write_text(TINY.replace('seed = 3', 'seed = 3\nneat_config = "fz.cfg"'))
        before = snapshot(work)
        code, err = run_cli(evolve_main, ["fz.toml", "--out", "new", "--workers", "1", "--no-progress"])
        check(work, before, code, err, new_outputs(work))


def prop_evolve_command_line(base, data) -> None:
    paths = ["new", "empty", "partial", "run", "afile", "fz.toml", "run/checkpoints/gen-0002.ckpt",
             "run/champion.json", "missing.toml"]
    with workspace(base) as work:
        drawn = draw_args(data, ["--out", "--workers", "--resume", "--resume-from", "--backend", "--max-retries",
                                 "--name", "--method", "--objectives", "--seed", "--generations", "--population",
                                 "--trials", "--environment", "--steps", "--robots"], paths)
        if data.draw(st.booleans(), label="positional"):
            drawn.insert(0, data.draw(st.sampled_from(paths), label="experiment"))
        resuming = "--resume" in drawn or "--resume-from" in drawn
        small = [] if resuming else ["--steps", "20", "--robots", "3", "--population", "2", "--generations", "1",
                                     "--trials", "1"]
        before = snapshot(work)
        code, err = run_cli(evolve_main, [*small, "--workers", "1", "--no-progress", *drawn])
        check(work, before, code, err, new_outputs(work) + (["run"] if resuming else []))


def prop_checkpoint(base, data) -> None:
    with workspace(base) as work:
        ckpts = sorted((work / "run" / "checkpoints").glob("*.ckpt"))
        for path in data.draw(st.lists(st.sampled_from(ckpts), min_size=1, max_size=len(ckpts), unique=True),
                              label="damaged"):
            blob = path.read_bytes()
            kind = data.draw(st.sampled_from(["truncate", "flip", "header", "delete", "empty", "garbage"]))
            at = data.draw(st.integers(0, len(blob) - 1), label="at")
            if kind == "truncate":
                path.write_bytes(blob[:at])
            elif kind == "flip":
                path.write_bytes(blob[:at] + bytes([blob[at] ^ 0xFF]) + blob[at + 1:])
            elif kind == "header":
                path.write_bytes(b"GATHERING-CHECKPOINT 9 abc\n" + blob.partition(b"\n")[2])
            elif kind == "delete":
                path.unlink()
            elif kind == "empty":
                path.write_bytes(b"")
            else:
                path.write_bytes(os.urandom(64))
        for name in data.draw(st.lists(st.sampled_from(["champion.json", "experiment.json", "stats.jsonl",
                                                        "neat.cfg"]), unique=True), label="deleted"):
            (work / "run" / name).unlink()
        before = snapshot(work)
        extra = data.draw(st.sampled_from([[], ["--generations", "3"], ["--generations", "1"]]), label="extra")
        code, err = run_cli(evolve_main, ["--resume", "run", "--workers", "1", "--no-progress", *extra])
        check(work, before, code, err, ["run"])


def prop_champion(base, data) -> None:
    with workspace(base) as work:
        doc = mutate_json(data, json.loads((work / "run" / "champion.json").read_text()))
        text = json.dumps(doc)
        if data.draw(st.booleans(), label="truncate"):
            text = text[: data.draw(st.integers(0, len(text)), label="cut")]
        (work / "champ.json").write_text(text)
        before = snapshot(work)
        drawn = draw_args(data, ["--environment", "--steps", "--seed", "--out", "--frame-every", "--fps", "--png"],
                          ["t.gif", "t.mp4", "p.png", "afile", "run", "run/champion.json", "new/x.gif"])
        code, err = run_cli(replay_main, ["champ.json", "--steps", "5", "--frame-every", "5", "--out", "t.gif",
                                          *drawn])
        check(work, before, code, err, new_outputs(work))


def prop_analysis_input(base, data) -> None:
    with workspace(base) as work:
        run = work / "run"
        target = data.draw(st.sampled_from(["stats", "champion", "experiment", "front"]), label="target")
        if target == "stats":
            text = (run / "stats.jsonl").read_text()
            (run / "stats.jsonl").write_text(mutate_lines(data, text, ["{}", "[]", "1", "{\"generation\": 0}", ""],
                                                          ["x"]) if data.draw(st.booleans())
                                             else text[: data.draw(st.integers(0, len(text)))])
        elif target in ("champion", "experiment"):
            path = run / f"{target}.json"
            path.write_text(json.dumps(mutate_json(data, json.loads(path.read_text()))))
        else:
            (run / "front").mkdir(exist_ok=True)
            (run / "front" / "genome-1.json").write_text(json.dumps(data.draw(st.sampled_from(JSON_VALUES))))
        before = snapshot(work)
        runs = data.draw(st.lists(st.sampled_from(["run", "run", "./run", "afile", "missing", "empty", "partial"]),
                                  min_size=1, max_size=3), label="runs")
        out = data.draw(st.sampled_from(["rep", "empty", "run", "afile", "partial"]), label="out")
        code, err = run_cli(analyze_main, [*runs, "--out", out])
        # the one file analysis adds to a run directory: its re-evaluation cache
        check(work, before, code, err, new_outputs(work) + [f"run/{REEVALUATION_CACHE}"])


def prop_compare_command_line(base, data) -> None:
    with workspace(base) as work:
        drawn = draw_args(data, ["--policy", "--environment", "--steps", "--robots", "--episodes", "--seed", "--out"],
                          ["champion:run/champion.json", "champion:run", "ppo:fz.toml", "ppo:missing.zip",
                           "champion:", "cmp", "run", "afile", "partial"])
        before = snapshot(work)
        code, err = run_cli(compare_main, ["--policy", "random", "--steps", "5", "--robots", "3", "--episodes", "1",
                                           "--out", "cmp", *drawn])
        check(work, before, code, err, new_outputs(work))


PROPERTIES = {  # name: (property, examples in the fast suite; -m slow runs 20 times more)
    "experiment_file": (prop_experiment_file, 10),
    "neat_config": (prop_neat_config, 6),
    "evolve_command_line": (prop_evolve_command_line, 12),
    "checkpoint": (prop_checkpoint, 5),
    "champion": (prop_champion, 10),
    "analysis_input": (prop_analysis_input, 8),
    "compare_command_line": (prop_compare_command_line, 6),
}


def _make(prop, examples: int, slow: bool):
    from hypothesis import given

    options = dict(FAST, derandomize=not slow)

    @settings(max_examples=examples, **options)
    @given(data=st.data())
    def test(base, data):
        prop(base, data)

    if slow:  # other examples than the fast run's, from a fixed seed (reproducible)
        test = seed(20261201)(test)

    test.__doc__ = prop.__name__
    return pytest.mark.slow(test) if slow else test


for _name, (_prop, _examples) in PROPERTIES.items():
    globals()[f"test_fuzz_{_name}"] = _make(_prop, _examples, slow=False)
    globals()[f"test_fuzz_{_name}_many"] = _make(_prop, 20 * _examples, slow=True)
