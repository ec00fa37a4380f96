"""The built wheel works as a new user gets it: installed (not editable) into a fresh virtualenv,
run from a directory outside the repository, presets by name, --list and --dump.

No download: the wheel is built without build isolation (setuptools of the running
interpreter) and installed with --no-deps; the fresh virtualenv sees the running
interpreter's site-packages (numpy, pymunk, neat-python, ...) through a .pth file placed
after its own site-packages, so its gathering_env/evolution are the wheel's.
"""

import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# what the wheel is built from (pyproject.toml names DESCRIPTION.md and LICENSE)
SOURCES = ("pyproject.toml", "DESCRIPTION.md", "LICENSE", "gathering_env", "evolution", "configs")


@pytest.mark.slow
def test_wheel_in_a_fresh_virtualenv(tmp_path):
    # build from a copy, so the checkout gets no build/ or egg-info
    src = tmp_path / "src"
    src.mkdir()
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy2(path, src / name)
    dist = tmp_path / "dist"
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                            "--quiet", str(src), "-w", str(dist)], capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stderr
    (wheel,) = dist.glob("gathering_evolution-*.whl")

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    vpy = venv / "bin" / "python"
    purelib = subprocess.run([str(vpy), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    outer = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (Path(purelib) / "outer_site.pth").write_text("\n".join(sorted(outer)) + "\n", encoding="utf-8")
    installed = subprocess.run([sys.executable, "-m", "pip", "--python", str(vpy), "install", "--no-deps",
                                "--no-index", "--quiet", str(wheel)], capture_output=True, text=True, timeout=600)
    assert installed.returncode == 0, installed.stderr

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    evolve = str(venv / "bin" / "gathering-evolve")
    env = {"PATH": f"{venv / 'bin'}:/usr/bin:/bin", "HOME": str(tmp_path),
           "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}

    where = subprocess.run([str(vpy), "-c", "import gathering_env, evolution.run.experiment as e; "
                            "print(gathering_env.__file__); print(e.CONFIG_DIR); print(gathering_env.__version__)"],
                           cwd=elsewhere, env=env, capture_output=True, text=True)
    assert where.returncode == 0, where.stderr
    module, presets, version = where.stdout.split()
    assert module.startswith(purelib) and presets == str(Path(purelib) / "evolution" / "presets")
    assert version == _checkout_version()

    out = elsewhere / "run"
    run = subprocess.run([evolve, "quick", "--generations", "1", "--workers", "1", "--no-progress",
                          "--out", str(out)], cwd=elsewhere, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert (out / "champion.json").is_file() and (out / "stats.jsonl").read_text().count("\n") == 1

    listed = subprocess.run([evolve, "--list"], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert listed.returncode == 0, listed.stderr
    names = {line.split()[0] for line in listed.stdout.splitlines()}
    assert {"S1", "S2", "S3", "M1", "M2", "M3", "quick", "hyperneat_m.neat.cfg"} <= names

    dumped = subprocess.run([evolve, "--dump", "S1"], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert dumped.stdout == (ROOT / "configs" / "S1.toml").read_text(encoding="utf-8")
    (elsewhere / "my.toml").write_text(dumped.stdout, encoding="utf-8")
    mine = subprocess.run([evolve, "my.toml", "--generations", "1", "--population", "4", "--steps", "100",
                           "--workers", "1", "--no-progress", "--out", "mine"],
                          cwd=elsewhere, env=env, capture_output=True, text=True, timeout=600)
    assert mine.returncode == 0, mine.stderr

    unknown = subprocess.run([evolve, "S9"], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert unknown.returncode == 2 and unknown.stderr.count("\n") == 1 and "quick" in unknown.stderr


def _checkout_version():
    import gathering_env

    return gathering_env.__version__
