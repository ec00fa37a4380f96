"""Peak memory of a replay against its number of frames: frames are streamed to the encoder.

    python benchmarks/bench_replay.py [--frames 100 1000] [--size 640] [--suffix .gif]

Each replay runs in a fresh process (so each peak is its own): a hand-made champion (ten
cameras, a random single-layer controller, 20 robots, environment 1) replayed by
``evolution.replay.replay`` with one frame per step (``--frame-every 1``) at the default view
(``--size`` 640 plus the information panel), written to a GIF (or ``--suffix .mp4``). Prints, per
frame count, the peak resident set size (``ru_maxrss``), the wall-clock time and the file size;
memory flat in the number of frames means the difference between the rows is small next to
the size of the frames themselves (a 640-pixel frame with its panel is about 1.6 MB, so
1 000 frames held in memory would be 1.6 GB).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def one_replay(frames: int, size: int, suffix: str, folder: Path) -> dict:
    """Replay ``frames - 1`` steps (one frame each, plus the first) in this process."""
    import numpy as np

    from evolution.encodings.controller import TeamController
    from evolution.replay import replay
    from evolution.run.champion import FORMAT, VERSION, load_champion
    from gathering_env import Morphology, SensorSpec

    sensors = [SensorSpec("camera", bearing=b, orientation=0.0, range=20.0, fov=math.pi / 2)
               for b in np.linspace(-math.pi, math.pi, 10, endpoint=False)]
    rng = np.random.default_rng(0)
    controller = TeamController.single_layer(rng.normal(size=(2, 10)), rng.normal(size=2))
    path = folder / "champion.json"
    path.write_text(json.dumps({"format": FORMAT, "version": VERSION, "method": "hyperneat-m", "experiment": "bench",
                                "objectives": {"task": 0.0}, "morphology": Morphology(sensors).to_dict(),
                                "controller": controller.to_dict(),
                                "environment": {"environment": 1, "max_cycles": frames - 1, "num_robots": 20}}))
    champion = load_champion(path)
    out = folder / f"replay{suffix}"
    start = time.perf_counter()
    _, _, written = replay(champion, dict(champion.environment), 0, out, frame_every=1, fps=15,
                           render_options={"size_px": size})
    seconds = time.perf_counter() - start
    return {"frames": written, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "seconds": seconds, "file_mb": out.stat().st_size / 2**20}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--size", type=int, default=640)
    parser.add_argument("--suffix", choices=(".gif", ".mp4"), default=".gif")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        with tempfile.TemporaryDirectory() as folder:
            print(json.dumps(one_replay(args.frames[0], args.size, args.suffix, Path(folder))))
        return
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(ROOT)}
    print(f"replay, {args.size}-pixel view + panel, one frame per step, {args.suffix}")
    print(f"{'frames':>7} {'peak RSS (MB)':>14} {'seconds':>8} {'file (MB)':>10}")
    for frames in args.frames:
        done = subprocess.run([sys.executable, __file__, "--child", "--frames", str(frames), "--size",
                               str(args.size), "--suffix", args.suffix], env=env, capture_output=True, text=True,
                              check=True)
        row = json.loads(done.stdout.strip().splitlines()[-1])
        print(f"{row['frames']:>7} {row['peak_rss_mb']:>14.0f} {row['seconds']:>8.1f} {row['file_mb']:>10.1f}")


if __name__ == "__main__":
    main()
