"""The source distribution is the whole project and runs its own tests; nothing in the project
refers to a file or a discussion outside it.

The slow test builds the sdist as a user or a package index would (``python -m build --sdist``,
without build isolation, so nothing is downloaded), checks that it holds every file of the
project, that its long description has no relative link, and runs a fast subset of its tests
from the unpacked folder (fixtures from conftest.py, the shared runs of small_runs.py, both
kernels).
"""

from __future__ import annotations

import email
import os
import re
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# What is not project source: local state, build output, caches.
NOT_SOURCE_DIRS = {".git", ".venv", "out", "runs", "build", "dist", "__pycache__", ".pytest_cache",
                   ".hypothesis", ".ruff_cache", "compare"}
NOT_SOURCE_SUFFIXES = (".pyc", ".egg-info")
# A fast subset that needs the test helpers: conftest's both_kernels fixture (scoring),
# small_runs' shared run directories (reevaluate), the shipped presets (presets).
SUBSET = ["tests/test_scoring.py", "tests/test_reevaluate.py", "tests/test_presets.py"]
# References a reader of this repository cannot follow.
OUTSIDE = re.compile(r"/work/|\.\./shared|\bSPEC\b|\b[Ii]ssue \d+|\(issue\b")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".cfg", ".cff", ".txt", ".in", ".yml", ".yaml", ""}


def project_files(root: Path) -> set[str]:
    """Relative paths of the project's files under ``root`` (no local state, caches or builds)."""
    found = set()
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [d for d in dirnames if d not in NOT_SOURCE_DIRS and not d.endswith(NOT_SOURCE_SUFFIXES)]
        for name in filenames:
            if not name.endswith(NOT_SOURCE_SUFFIXES) and name not in NOT_SOURCE_DIRS:
                found.add(Path(dirpath, name).relative_to(root).as_posix())
    return found


def relative_links(markdown: str) -> list[str]:
    """Targets of markdown links and images that are not absolute URLs."""
    targets = re.findall(r"\]\(([^)\s]+)", markdown) + re.findall(r"<img[^>]*src=\"([^\"]+)", markdown)
    return [t for t in targets if not re.match(r"[a-z][a-z0-9+.-]*://|mailto:|#", t)]


def test_relative_links_finds_what_a_package_index_cannot_follow():
    text = "see [docs](docs/index.md), ![x](docs/a.png), [web](https://example.org/a) and [top](#quick)"
    assert relative_links(text) == ["docs/index.md", "docs/a.png"]


def test_the_long_description_has_no_relative_link():
    import tomllib
    readme = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["readme"]
    assert relative_links((ROOT / readme).read_text(encoding="utf-8")) == []


def test_nothing_refers_outside_the_repository():
    here = Path(__file__).relative_to(ROOT).as_posix()
    hits = []
    for rel in sorted(project_files(ROOT) - {here}):
        if Path(rel).suffix not in TEXT_SUFFIXES:
            continue
        for number, line in enumerate((ROOT / rel).read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            if OUTSIDE.search(line):
                hits.append(f"{rel}:{number}: {line.strip()}")
    assert hits == [], "\n".join(hits)


@pytest.mark.slow
def test_sdist_holds_the_project_and_runs_its_tests(tmp_path):
    pytest.importorskip("build")
    src = tmp_path / "src"
    files = project_files(ROOT)
    for rel in files:  # build from a copy, so the checkout gets no egg-info
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / rel, src / rel)
    dist = tmp_path / "dist"
    built = subprocess.run([sys.executable, "-m", "build", "--sdist", "--no-isolation", "--outdir", str(dist),
                            str(src)], capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stdout[-2000:] + built.stderr[-2000:]
    (archive,) = dist.glob("gathering_evolution-*.tar.gz")
    unpacked = tmp_path / "unpacked"
    with tarfile.open(archive) as tar:
        tar.extractall(unpacked, filter="data")
    (top,) = unpacked.iterdir()

    shipped = project_files(top)
    missing = sorted(files - shipped)
    assert missing == [], f"not in the sdist: {missing}"
    for needed in ("tests/conftest.py", "tests/small_runs.py", "docs/model.md", "Makefile", "CITATION.cff",
                   "examples/random_episode.py", "benchmarks/bench_env.py", ".ci/run"):
        assert needed in shipped

    metadata = email.message_from_string((top / "PKG-INFO").read_text(encoding="utf-8"))
    assert relative_links(metadata.get_payload()) == []

    env = {**os.environ, "PYTHONPATH": str(top), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *SUBSET],
                         cwd=top, env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    summary = run.stdout.strip().splitlines()[-1]
    assert re.search(r"\d+ passed", summary) and "error" not in summary, summary
    # the tests ran the unpacked code, not the checkout's
    where = subprocess.run([sys.executable, "-c", "import gathering_env, evolution.run.experiment as e; "
                            "print(gathering_env.__file__); print(e.CONFIG_DIR)"],
                           cwd=top, env=env, capture_output=True, text=True, check=True).stdout.split()
    assert where == [str(top / "gathering_env" / "__init__.py"), str(top / "configs")]


def code_map_paths(readme: str) -> set[str]:
    """Paths named by the README's code map (a tree: two spaces per level, folders end in /)."""
    block = readme.split("## Code map", 1)[1].split("```", 2)[1]
    stack: list[tuple[int, str]] = []
    named = set()
    for line in block.splitlines():
        if not line.strip():
            continue
        indent = len(line) - len(line.lstrip(" "))
        name = line.split()[0]
        while stack and stack[-1][0] >= indent:
            stack.pop()
        path = "".join(folder for _, folder in stack) + name
        named.add(path.rstrip("/"))
        if name.endswith("/"):
            stack.append((indent, name))
    return named


def test_code_map_parser_rebuilds_nested_paths():
    text = "## Code map\n\n```\npkg/   a\n  sub/   b\n    m.py   c\n  rl/sb3.py   d\ntop.py   e\n```\n"
    assert code_map_paths(text) == {"pkg", "pkg/sub", "pkg/sub/m.py", "pkg/rl/sb3.py", "top.py"}


def test_readme_code_map_names_every_module():
    named = code_map_paths((ROOT / "README.md").read_text(encoding="utf-8"))
    modules = {p.relative_to(ROOT).as_posix() for package in ("gathering_env", "evolution")
               for p in (ROOT / package).rglob("*.py") if "__pycache__" not in p.parts}
    # a subpackage's __init__.py is named by its folder, or by a module under it (rl/sb3.py)
    folders = {n.rsplit("/", 1)[0] for n in named if "/" in n} | named
    missing = sorted(m for m in modules if m not in named and not (m.endswith("/__init__.py")
                                                                   and m.rsplit("/", 1)[0] in folders))
    assert missing == []
    assert sorted(n for n in named if n.endswith(".py") and n not in modules) == []  # no stale names
