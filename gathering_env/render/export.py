"""Writing pictures and videos: ``save_png``, ``save_video`` (GIF, or MP4 with ``imageio-ffmpeg``).

``_check_frames`` is the one check of a frame sequence (``save_video``, ``film_strip``): one or
more ``(H, W, 3)`` arrays of one shape, or a ValueError naming the caller. imageio is imported
when a file is written.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def _check_frames(who: str, frames) -> list[np.ndarray]:
    """The frames as arrays, all of one ``(H, W, 3)`` shape, or a ValueError naming ``who``."""
    arrays = [np.asarray(f) for f in frames]
    if not arrays:
        raise ValueError(f"{who}: no frames; allowed: one or more frames")
    shape = arrays[0].shape
    if len(shape) != 3 or shape[2] != 3:
        raise ValueError(f"{who}: frames must have shape (H, W, 3); frame 0 has {shape}")
    for i, a in enumerate(arrays):
        if a.shape != shape:
            raise ValueError(f"{who}: frame {i} has shape {a.shape}; frame 0 has {shape}")
    return arrays


def save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    """Write an ``(H, W, 3)`` uint8 image as PNG (parent folders are created)."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"picture file {str(path)!r} has suffix {path.suffix!r}; allowed: '.png'")
    import imageio.v2 as imageio

    path.parent.mkdir(parents=True, exist_ok=True)
    imageio.imwrite(path, np.asarray(image, dtype=np.uint8))
    return path


def save_video(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: int = 20) -> Path:
    """Write frames to a ``.gif`` (imageio + pillow) or ``.mp4`` (needs ``imageio-ffmpeg``).

    Args:
        frames: equally shaped ``(H, W, 3)`` uint8 arrays, e.g. from ``Renderer.render``.
        path: output file; the suffix picks the format. Parent folders are created.
        fps: playback rate (frames per second, > 0).

    Returns:
        The path written.

    Raises:
        ValueError: no frames, frames of different or wrong shapes, a bad ``fps``, an
            unsupported suffix, or ``.mp4`` without ``imageio-ffmpeg`` (``pip install imageio-ffmpeg``).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"video file {str(path)!r} has suffix {suffix!r}; allowed: '.gif', '.mp4'")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
        raise ValueError(f"save_video: fps={fps!r}; allowed: a number > 0")
    arrays = _check_frames("save_video", frames)
    arrays = [a if a.dtype == np.uint8 else np.clip(a, 0, 255).astype(np.uint8) for a in arrays]

    import imageio.v2 as imageio

    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                "writing .mp4 needs ffmpeg through imageio-ffmpeg: pip install imageio-ffmpeg "
                "(or the project's 'video' extra); .gif works without it"
            ) from None
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        imageio.mimsave(path, arrays, duration=1000.0 / fps, loop=0)
    else:
        h, w = arrays[0].shape[:2]
        if h % 2 or w % 2:     # H.264 in yuv420p needs even sizes: pad by repeating the edge
            arrays = [np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") for a in arrays]
        imageio.mimsave(path, arrays, fps=fps, macro_block_size=1)
    return path
