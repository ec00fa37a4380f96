"""The documentation's code blocks run as written, so the docs cannot rot.

Collected: the fenced ```python, ```bash / ```sh / ```shell and ```console blocks of README.md
and docs/*.md (in a ```console block only the lines starting with "$ " are commands), and the
```toml blocks holding an [experiment] section (loaded as experiment files).

Marker convention (an HTML comment on the nearest non-blank line before the opening fence):

    <!-- slow -->                 run the block only in the slow suite (make test-slow)
    <!-- skip-test: reason -->    never run the block (a cluster, hours of CPU, the tests
                                  themselves); the reason is required

Unmarked blocks run in the fast suite, so keep them to seconds.

How blocks run: a page's blocks run in order, in one scratch directory per page (a block may
use what an earlier block of the same page wrote) holding links to the repository's configs/,
examples/ and benchmarks/. Python blocks run in a subprocess of this interpreter with the
checkout under test first on PYTHONPATH; shell blocks run under `bash -e -o pipefail` with a
directory first on PATH whose `python` is this interpreter and whose `gathering-*` commands are
wrappers around this checkout's entry points (read from [project.scripts] of pyproject.toml).
So the blocks exercise this checkout whether or not, and from wherever, the package is installed
(CI installs it editable; a developer's venv may point at another checkout).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SHELL = {"bash", "sh", "shell", "console"}
RUN_LANGS = SHELL | {"python"}
MARKER = re.compile(r"^<!--\s*(slow|skip-test)\s*(?::\s*(.*?))?\s*-->$")
FENCE = re.compile(r"^(\s*)```\s*([\w+-]*)\s*$")
LINKED_INTO_WORKDIR = ("configs", "examples", "benchmarks", "docs")   # docs: blocks read its evidence files
# Pages other engineers are writing at the same time: linked before they exist. Remove a name
# once its page is in the repository.
PENDING_PAGES: set[str] = set()
BLOCK_TIMEOUT = 1800  # seconds; a hang guard only, nothing is timed


@dataclass(frozen=True)
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    lang: str
    code: str
    mark: str | None  # None, "slow" or "skip-test"
    reason: str | None

    @property
    def where(self) -> str:
        page = self.page.relative_to(ROOT) if self.page.is_relative_to(ROOT) else self.page.name
        return f"{page}:{self.line}"


def collect(page: Path) -> list[Block]:
    """Fenced code blocks of a Markdown page, with the marker comment before each."""
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if not opening:
            i += 1
            continue
        indent, lang = opening.group(1), opening.group(2).lower()
        j = i + 1
        while j < len(lines) and lines[j].strip() != "```":
            j += 1
        body = [line[len(indent):] if line.startswith(indent) else line for line in lines[i + 1 : j]]
        k = i - 1
        while k >= 0 and not lines[k].strip():
            k -= 1
        marker = MARKER.match(lines[k].strip()) if k >= 0 else None
        blocks.append(Block(page, i + 1, lang, "\n".join(body) + "\n",
                            marker.group(1) if marker else None, marker.group(2) if marker else None))
        i = j + 1
    return blocks


def _shell_code(block: Block) -> str:
    if block.lang != "console":
        return block.code
    return "".join(line[2:] + "\n" for line in block.code.splitlines() if line.startswith("$ "))


@pytest.fixture(scope="module")
def tool_dir(tmp_path_factory) -> Path:
    """`python` and the `gathering-*` commands of this checkout, to put first on PATH."""
    bin_dir = tmp_path_factory.mktemp("docs-bin")
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["scripts"]
    for name, target in scripts.items():
        module, func = target.split(":")
        (bin_dir / name).write_text(
            f"#!{sys.executable}\nimport sys\nsys.path.insert(0, {str(ROOT)!r})\n"
            f"from {module} import {func}\nsys.argv[0] = {name!r}\nsys.exit({func}())\n", encoding="utf-8")
    for name in ("python", "python3"):
        (bin_dir / name).write_text(f'#!/bin/sh\nexec {sys.executable} "$@"\n', encoding="utf-8")
    for path in bin_dir.iterdir():
        path.chmod(0o755)
    return bin_dir


def _run_page(page: Path, marks: set[str | None], workdir: Path, bin_dir: Path) -> int:
    for name in LINKED_INTO_WORKDIR:
        (workdir / name).symlink_to(ROOT / name, target_is_directory=True)
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    env.update(SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy", MPLBACKEND="Agg")
    ran = 0
    for n, block in enumerate(collect(page)):
        if block.mark not in marks:
            continue
        if block.lang == "python":
            script = workdir / f"block{n}.py"
            script.write_text(block.code, encoding="utf-8")
            cmd = [sys.executable, str(script)]
        elif block.lang in SHELL:
            cmd = ["bash", "-e", "-o", "pipefail", "-c", _shell_code(block)]
        elif block.lang == "toml" and "[experiment]" in block.code:
            from evolution.run.experiment import load_experiment

            experiment_file = workdir / f"block{n}.toml"
            experiment_file.write_text(block.code, encoding="utf-8")
            load_experiment(experiment_file)  # raises naming the key if the example is stale
            ran += 1
            continue
        else:
            continue
        result = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True,
                                timeout=BLOCK_TIMEOUT)
        assert result.returncode == 0, (
            f"{block.where}: the {block.lang} block failed (exit {result.returncode})\n"
            f"--- block ---\n{block.code}--- stdout ---\n{result.stdout[-3000:]}\n"
            f"--- stderr ---\n{result.stderr[-3000:]}")
        ran += 1
    return ran


def _page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


@pytest.mark.parametrize("page", PAGES, ids=_page_id)
def test_fast_blocks_run(page, tmp_path, tool_dir):
    _run_page(page, {None}, tmp_path, tool_dir)


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=_page_id)
def test_all_blocks_run(page, tmp_path, tool_dir):
    """Fast and slow blocks in page order (a slow block may use what a fast one wrote)."""
    _run_page(page, {None, "slow"}, tmp_path, tool_dir)


def test_markers_are_well_formed():
    problems = []
    for page in PAGES:
        lines = page.read_text(encoding="utf-8").splitlines()
        fence_lines = {block.line for block in collect(page)}
        for number, line in enumerate(lines, 1):
            if not line.strip().startswith("<!--") or not re.search(r"slow|skip", line):
                continue
            marker = MARKER.match(line.strip())
            if not marker:
                problems.append(f"{page.name}:{number}: malformed marker {line.strip()!r}")
                continue
            if marker.group(1) == "skip-test" and not marker.group(2):
                problems.append(f"{page.name}:{number}: skip-test without a reason")
            following = next((n for n in range(number + 1, len(lines) + 1) if lines[n - 1].strip()), None)
            if following not in fence_lines:
                problems.append(f"{page.name}:{number}: marker not followed by a code block")
    assert not problems, "\n".join(problems)


def test_every_runnable_language_is_known():
    """A typo in a fence language (```pyhton) would silently skip a block."""
    known = RUN_LANGS | {"toml", "text", ""}
    unknown = [f"{b.where}: ```{b.lang}" for page in PAGES for b in collect(page) if b.lang not in known]
    assert not unknown, unknown


def test_collect_reads_markers_indented_blocks_and_console(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "# t\n\n```python\nprint(1)\n```\n\n<!-- slow -->\n\n```bash\necho a\n```\n"
        "* item\n\n  ```python\n  x = 1\n  ```\n<!-- skip-test: needs a cluster -->\n"
        "```console\n$ echo b\nb\n```\n", encoding="utf-8")
    blocks = collect(page)
    assert [(b.lang, b.mark, b.line) for b in blocks] == [
        ("python", None, 3), ("bash", "slow", 9), ("python", None, 14), ("console", "skip-test", 18)]
    assert blocks[2].code == "x = 1\n"
    assert blocks[3].reason == "needs a cluster" and _shell_code(blocks[3]) == "echo b\n"


def test_pages_open_with_what_they_cover():
    for page in sorted((ROOT / "docs").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        title, _, rest = text.partition("\n")
        assert title.startswith("# "), f"{page.name}: no title line"
        first_paragraph = rest.strip().split("\n\n")[0]
        # an opening paragraph of prose, not a heading, code block, picture or table
        assert first_paragraph[:1].isalpha() and len(first_paragraph) > 80, (
            f"{page.name}: does not open with a paragraph on what it covers")


def test_relative_links_resolve():
    link = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
    missing = []
    for page in PAGES:
        for target in link.findall(page.read_text(encoding="utf-8")):
            if re.match(r"[a-z]+:", target):
                continue  # a URL
            path = (page.parent / target).resolve()
            if not path.exists() and path.relative_to(ROOT).as_posix() not in PENDING_PAGES:
                missing.append(f"{page.relative_to(ROOT)}: {target}")
    assert not missing, missing


def heading_anchors(page: Path) -> set[str]:
    """The anchors a Markdown renderer makes of a page's headings (lowercase, punctuation but
    hyphens dropped, spaces to hyphens, a repeated one numbered), code blocks skipped."""
    found: set[str] = set()
    counts: dict[str, int] = {}
    fenced = False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            fenced = not fenced
        heading = None if fenced else re.match(r"#{1,6} (.*)", line)
        if heading:
            slug = re.sub(r"[^\w\- ]", "", heading.group(1).strip().lower()).replace(" ", "-")
            found.add(slug if slug not in counts else f"{slug}-{counts[slug]}")
            counts[slug] = counts.get(slug, 0) + 1
    return found


def test_links_to_a_section_name_one_that_exists():
    link = re.compile(r"\]\(([^)#\s]*)#([^)\s]+)\)")
    broken = []
    for page in PAGES:
        for target, anchor in link.findall(page.read_text(encoding="utf-8")):
            destination = page if not target else (page.parent / target).resolve()
            if re.match(r"[a-z]+:", target) or destination.suffix != ".md" or not destination.exists():
                continue
            if anchor not in heading_anchors(destination):
                broken.append(f"{page.relative_to(ROOT)}: {target}#{anchor}")
    assert not broken, broken


def test_a_failing_block_fails_and_blocks_use_this_checkout(tmp_path, tool_dir):
    page = tmp_path / "page.md"
    page.write_text(
        "```python\nimport importlib.util, pathlib\n"  # finds the package without importing it
        "origin = pathlib.Path(importlib.util.find_spec('evolution').origin).resolve()\n"
        f"assert origin.parent.parent == pathlib.Path({str(ROOT)!r}), origin\n```\n"
        f"```bash\ngrep -q {str(ROOT)!r} \"$(command -v gathering-evolve)\"\ntest \"$(command -v python)\" != \"\"\n```\n"
        "<!-- slow -->\n```bash\nexit 3\n```\n", encoding="utf-8")
    (tmp_path / "fast").mkdir()
    assert _run_page(page, {None}, tmp_path / "fast", tool_dir) == 2
    (tmp_path / "all").mkdir()
    with pytest.raises(AssertionError, match=r"page.md:\d+: the bash block failed \(exit 3\)"):
        _run_page(page, {None, "slow"}, tmp_path / "all", tool_dir)
