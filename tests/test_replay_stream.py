"""Replays stream their frames to the encoder: memory flat in the number of frames (slow:
1 000 frames), the file complete or absent (a full disk leaves no truncated GIF and keeps an
earlier one), ``--size`` bounded, one-line errors naming the file."""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
import pytest
from test_hardening import call, one_error_line
from test_replay_figures import champion  # noqa: F401  (fixture)

from evolution.cli import replay_main
from gathering_env.render import VideoWriter, save_video
from gathering_env.render import export as export_module

ROOT = Path(__file__).resolve().parent.parent


def frames(count: int, h: int = 48, w: int = 64) -> list[np.ndarray]:
    """Frames of 40 colours (a GIF palette holds them exactly), each shifted: all different."""
    rng = np.random.default_rng(3)
    colours = rng.integers(0, 256, (40, 3), dtype=np.uint8)
    base = colours[rng.integers(0, 40, (h, w))]
    return [np.roll(base, 3 * i, axis=1) for i in range(count)]


def test_streamed_gif_holds_every_frame_in_order(tmp_path):
    shown = frames(7)
    path = save_video(iter(shown), tmp_path / "a.gif", fps=10)   # a generator: streamed
    back = imageio.mimread(path)
    assert len(back) == 7
    for original, read in zip(shown, back):
        # a 256-colour palette per frame: the original, and closest to its own frame
        error = np.abs(read[..., :3].astype(int) - original.astype(int)).mean()
        assert error < 1
        assert all(error < np.abs(read[..., :3].astype(int) - other.astype(int)).mean()
                   for other in shown if other is not original)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif"]   # no temporary file left


def test_pixels_unchanged_since_the_previous_frame_keep_showing_it(tmp_path):
    """Unchanged pixels are written transparent: every frame still reads back whole, and a
    small moving square costs a fraction of redrawing every frame."""
    background = frames(1, h=96, w=128)[0]
    shown = []
    for i in range(6):
        frame = background.copy()
        frame[10 + 5 * i: 20 + 5 * i, 30 + 8 * i: 40 + 8 * i] = (255, 0, 0)
        shown.append(frame)
    path = save_video(shown, tmp_path / "square.gif", fps=10)
    back = imageio.mimread(path)
    assert len(back) == 6
    for original, read in zip(shown, back):
        assert np.abs(read[..., :3].astype(int) - original.astype(int)).max() == 0
    redrawn = save_video([np.roll(f, 1, axis=0) if i % 2 else f for i, f in enumerate(shown)], tmp_path / "all.gif")
    assert path.stat().st_size < 0.5 * redrawn.stat().st_size


def test_a_failed_write_leaves_no_partial_file_and_keeps_an_earlier_one(tmp_path, monkeypatch):
    earlier = save_video(frames(2), tmp_path / "a.gif")
    before = earlier.read_bytes()
    real_add = export_module._GifStream.add

    def add_until_the_disk_is_full(self, frame):
        if self.count == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_add(self, frame)

    monkeypatch.setattr(export_module._GifStream, "add", add_until_the_disk_is_full)
    with pytest.raises(OSError) as caught:
        save_video(frames(6), earlier)
    assert caught.value.filename == str(earlier) and caught.value.errno == errno.ENOSPC
    assert earlier.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif"]
    with pytest.raises(ValueError, match="frame 2 has shape"), VideoWriter(tmp_path / "b.gif") as video:
        for frame in frames(2) + [frames(1, h=50)[0]]:
            video.add(frame)
    assert not (tmp_path / "b.gif").exists() and sorted(p.name for p in tmp_path.iterdir()) == ["a.gif"]


def test_replay_on_a_full_disk_is_one_line_naming_the_file(champion, tmp_path, capsys, monkeypatch):  # noqa: F811
    out = tmp_path / "team.gif"

    def full(self, frame):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(export_module._GifStream, "add", full)
    assert call(replay_main, [str(champion), "--out", str(out), "--size", "64"]) == 2
    err = one_error_line(capsys)
    assert err.startswith(f"error: {out}: no space left on device; allowed: free space")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["champion.json"]


@pytest.mark.skipif(sys.platform != "linux", reason="needs RLIMIT_FSIZE")
def test_replay_over_the_file_size_limit_is_one_line_and_leaves_nothing(champion, tmp_path):  # noqa: F811
    out = tmp_path / "team.gif"
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (30000, 30000)); "
            "from evolution.cli import replay_main; sys.exit(replay_main(sys.argv[1:]))")
    done = subprocess.run([sys.executable, "-c", code, str(champion), "--out", str(out), "--frame-every", "1"],
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy"})
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith(f"error: {out}: file too large")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["champion.json"]


@pytest.mark.slow
def test_replay_memory_is_flat_in_the_number_of_frames():
    """Peak RSS of a 1 000-frame replay against a 100-frame one (benchmarks/bench_replay.py):
    holding the frames would add 900 x 0.5 MB at this size; streaming adds next to nothing."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy"}
    peaks = {}
    for count in (100, 1000):
        done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_replay.py"), "--child", "--frames",
                               str(count), "--size", "256"], env=env, capture_output=True, text=True, check=True,
                              timeout=1800)
        row = json.loads(done.stdout.strip().splitlines()[-1])
        assert row["frames"] == count
        peaks[count] = row["peak_rss_mb"]
    frame_mb = 256 * (256 + 256 // 3) * 3 / 2**20
    assert peaks[1000] - peaks[100] < 0.1 * 900 * frame_mb, peaks
