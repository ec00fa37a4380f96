"""A local Ray started by the trainer lives and dies with it: no Ray process (GCS server,
raylet, agents, workers) outlives a SIGKILLed trainer, counted by PID; a local Ray that
cannot start says why in one line, with the cause Ray only wrote to its log."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from datetime import datetime, timedelta
from pathlib import Path

import pytest
from test_hardening import TINY, one_error_line, write_tiny

from evolution.cli import evolve_main
from evolution.run.reaper import descendants, process_table

ray = pytest.importorskip("ray")
ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")

# the lines a raylet refused its object store's mmap wrote (Ray itself only says "timed out")
RAYLET_OUT = """\
[2026-12-01 17:45:46,968 I 1260 1269] (raylet) dlmalloc.cc:153: create_and_mmap_buffer(7125729288, /dev/shm/plasmaXXXXXX)
[2026-12-01 17:45:46,968 E 1260 1269] (raylet) dlmalloc.cc:215: mmap failed with error: Cannot allocate memory
[2026-12-01 17:45:47,040 C 1260 1269] (raylet) plasma_allocator.cc:79:  Check failed: allocation.has_value()
"""


def cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return "?"


def still_alive(known: dict[int, int]) -> dict[int, int]:
    table = process_table()
    return {pid: start for pid, start in known.items() if table.get(pid, (0, None))[1] == start}


def test_local_ray_that_fails_to_start_names_the_cause_from_its_log(tmp_path, capsys, monkeypatch):
    exp = write_tiny(tmp_path)
    temp = tmp_path / "raytmp"
    now = datetime.now()
    logs = temp / "ray" / f"session_{now:%Y-%m-%d_%H-%M-%S_%f}_{os.getpid()}" / "logs"
    logs.mkdir(parents=True)
    old = temp / "ray" / f"session_{now - timedelta(minutes=5):%Y-%m-%d_%H-%M-%S_%f}_{os.getpid()}" / "logs"
    old.mkdir(parents=True)  # an earlier Ray of this process: its errors are not this start's
    (old / "raylet.out").write_text("[2026-12-01 17:40:00,000 E 1 2] (raylet) x.cc:1: an old error\n")
    (logs / "raylet.out").write_text(RAYLET_OUT)
    (logs / "gcs_server.out").write_text("[2026-12-01 17:45:45,001 I 1 2] (gcs_server) gcs.cc:1: started\n")
    monkeypatch.setenv("RAY_TMPDIR", str(temp))

    def timed_out(**kwargs):
        raise Exception("The current node timed out during startup. This could happen because some of the "
                        "raylet failed to startup or the GCS has become overloaded.")

    monkeypatch.setattr(ray, "init", timed_out)
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    assert evolve_main([str(exp), "--out", str(tmp_path / "r"), "--backend", "ray", "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert "Ray did not start (The current node timed out during startup" in err
    assert f"raylet: mmap failed with error: Cannot allocate memory (Ray's log {logs / 'raylet.out'})" in err
    assert "an old error" not in err
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_ray_under_a_memory_limit_fails_in_one_line_with_the_real_cause(tmp_path):
    exp = write_tiny(tmp_path)
    limit = 3 * 2**30  # the object store's mmap is refused under this address-space limit
    done = subprocess.run([sys.executable, "-m", "evolution", str(exp), "--out", str(tmp_path / "r"), "--backend",
                           "ray", "--workers", "1", "--no-progress"], env=ENV, capture_output=True, text=True,
                          timeout=300, preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and lines[-1].startswith("error: --backend ray: Ray did not start"), done.stderr
    assert "Traceback" not in done.stderr
    assert "mmap failed" in lines[-1] or "allocate memory" in lines[-1].lower(), lines[-1]
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_no_ray_process_outlives_a_sigkilled_trainer(tmp_path):
    exp = tmp_path / "slow.toml"
    exp.write_text(TINY.format(generations=200).replace("max_cycles = 150", "max_cycles = 3000"))
    out = tmp_path / "run"
    trainer = subprocess.Popen([sys.executable, "-m", "evolution", str(exp), "--out", str(out), "--backend", "ray",
                                "--workers", "2", "--no-progress"], env=ENV, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
    tree: dict[int, int] = {}
    try:
        deadline = time.monotonic() + 240
        while not (out / "checkpoints" / "gen-0001.ckpt").exists():  # Ray is up, its workers evaluated
            assert trainer.poll() is None and time.monotonic() < deadline, "the ray run did not get going"
            time.sleep(0.2)
        tree = descendants({trainer.pid}, process_table())
        names = " | ".join(cmdline(p) for p in tree)
        assert "raylet" in names and "gcs_server" in names, names
        assert len(tree) >= 5, names  # GCS, raylet, agents, workers, the reaper
        trainer.send_signal(signal.SIGKILL)
        trainer.wait(timeout=30)
        deadline = time.monotonic() + 30
        while still_alive(tree) and time.monotonic() < deadline:
            time.sleep(0.2)
        left = still_alive(tree)
        assert not left, "outlived the trainer: " + "; ".join(f"{p} {cmdline(p)[:80]}" for p in left)
    finally:
        if trainer.poll() is None:
            trainer.kill()
            trainer.wait()
        for pid in still_alive(tree):  # only if the test failed: never leave processes behind
            os.kill(pid, signal.SIGKILL)
