"""A full disk or a file too large is one line naming the file being written (never
``file system:``), and a run stopped by it resumes."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_hardening import one_error_line, write_tiny

from evolution.cli import evolve_main
from evolution.guard import describe_os_error, writing
from evolution.run.stats import read_stats

ROOT = Path(__file__).resolve().parent.parent


def test_writing_names_the_file_an_unnamed_error_was_about(tmp_path):
    with pytest.raises(OSError) as caught, writing(tmp_path / "a.txt"):
        raise OSError(errno.ENOSPC, "No space left on device")
    assert caught.value.filename == str(tmp_path / "a.txt") and caught.value.errno == errno.ENOSPC
    assert describe_os_error(caught.value).startswith(f"{tmp_path / 'a.txt'}: no space left on device; allowed: free")
    with pytest.raises(OSError) as kept, writing(tmp_path / "a.txt"):
        raise PermissionError(errno.EACCES, "Permission denied", "/elsewhere")
    assert kept.value.filename == "/elsewhere"  # an error that names its file keeps it


@pytest.mark.parametrize("target", ["stats.jsonl", "gen-0001.ckpt"])
def test_disk_full_mid_run_names_the_file_and_the_run_resumes(tmp_path, capsys, monkeypatch, target):
    exp = write_tiny(tmp_path, generations=3)
    run = tmp_path / "run"
    real_fsync = os.fsync
    fired = []

    def fsync(fd):
        if not fired and os.readlink(f"/proc/self/fd/{fd}").rsplit("/", 1)[-1].startswith(
                (target, f".{target}")):
            fired.append(fd)
            raise OSError(errno.ENOSPC, "No space left on device")  # as the kernel reports it: no file name
        return real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    assert evolve_main([str(exp), "--out", str(run), "--workers", "1", "--no-progress"]) == 2
    err = one_error_line(capsys)
    assert fired and "file system" not in err
    assert f"{run}/" in err and target in err and "no space left on device" in err and "--resume" in err
    monkeypatch.setattr(os, "fsync", real_fsync)
    assert evolve_main(["--resume", str(run), "--workers", "1", "--no-progress"]) == 0
    assert [r["generation"] for r in read_stats(run / "stats.jsonl")] == [0, 1, 2]


@pytest.mark.skipif(not hasattr(os, "setpgid") or sys.platform != "linux", reason="needs RLIMIT_FSIZE")
def test_file_too_large_names_the_file(tmp_path):
    exp = write_tiny(tmp_path, generations=2)
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000)); "
            "from evolution.cli import evolve_main; sys.exit(evolve_main(sys.argv[1:]))")
    done = subprocess.run([sys.executable, "-c", code, str(exp), "--out", str(tmp_path / "run"), "--workers", "1",
                           "--no-progress"], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy"})
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {tmp_path / 'run'}/"), done.stderr
    assert "file too large" in lines[0] and "file system" not in lines[0]
