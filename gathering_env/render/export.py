"""Writing pictures and videos: ``save_png``, ``save_video`` and the streaming ``VideoWriter``.

``VideoWriter`` encodes each frame as it arrives (a GIF through Pillow's GIF encoder, frame by
frame, each with its own palette and the pixels unchanged since the previous frame transparent;
an MP4 through ``imageio-ffmpeg``), so a replay's memory does
not grow with its number of frames. Every file is written to a hidden temporary file beside the
target and renamed over it only once complete: a failure (a full disk, a bad frame, Ctrl-C)
leaves no partial file and an earlier output intact, and its ``OSError`` names the target.
``_check_frames`` is the one check of a frame sequence (``save_video``, ``film_strip``): one or
more ``(H, W, 3)`` arrays of one shape, or a ValueError naming the caller. imageio and Pillow are
imported when a file is written.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

VIDEO_SUFFIXES = (".gif", ".mp4")


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


@contextlib.contextmanager
def _replacing(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it over ``path``, else delete it.

    An ``OSError`` that names no file (or the temporary one) is raised naming ``path``.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.partial-{os.getpid()}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException as err:
        with contextlib.suppress(OSError):
            tmp.unlink()
        named = _naming(err, path, tmp)
        if named is not err:
            raise named from None
        raise


def _naming(err: BaseException, path: Path, tmp: Path) -> BaseException:
    """``err``, or for an ``OSError`` naming no file (or ``tmp``) the same error naming ``path``."""
    if isinstance(err, OSError) and err.filename in (None, str(tmp)):
        return OSError(err.errno, err.strerror or str(err) or type(err).__name__, str(path))
    return err


def save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    """Write an ``(H, W, 3)`` uint8 image as PNG (parent folders are created; no partial file on failure)."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"picture file {str(path)!r} has suffix {path.suffix!r}; allowed: '.png'")
    import imageio.v2 as imageio

    with _replacing(path) as tmp:
        imageio.imwrite(tmp, np.asarray(image, dtype=np.uint8), format="PNG")
    return path


def _check_video_args(path: Path, fps: Any) -> str:
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ValueError(f"video file {str(path)!r} has suffix {suffix!r}; allowed: '.gif', '.mp4'")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
        raise ValueError(f"save_video: fps={fps!r}; allowed: a number > 0")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                "writing .mp4 needs ffmpeg through imageio-ffmpeg: pip install imageio-ffmpeg "
                "(or the project's 'video' extra); .gif works without it"
            ) from None
    return suffix


class _GifStream:
    """An animated GIF written frame by frame (Pillow's GIF header and frame encoders).

    Each frame gets its own palette of up to 255 colours; index 255 is transparent and marks
    the pixels equal to the previous frame (they keep showing it), so unchanged areas cost
    almost nothing, as in Pillow's own multi-frame writer. Only the previous frame is kept.
    """

    TRANSPARENT = 255

    def __init__(self, fp: IO[bytes], fps: float) -> None:
        self.fp, self.ms, self.count = fp, max(10, round(1000.0 / fps)), 0
        self._previous: np.ndarray | None = None

    def add(self, frame: np.ndarray) -> None:
        from PIL import GifImagePlugin, Image

        quantized = Image.fromarray(frame, "RGB").convert("P", palette=Image.Palette.ADAPTIVE, colors=255)
        palette = (quantized.getpalette() or [])[:3 * 255]
        palette += [0] * (3 * 256 - len(palette))
        index = np.asarray(quantized)
        if self._previous is not None:
            index = np.where((frame == self._previous).all(axis=2), np.uint8(self.TRANSPARENT), index)
        im = Image.fromarray(index.astype(np.uint8), "P")
        im.putpalette(palette)
        if self.count == 0:
            header, _ = GifImagePlugin.getheader(im, info={"loop": 0, "duration": self.ms})
            self.fp.write(b"".join(header))
        for chunk in GifImagePlugin.getdata(im, duration=self.ms, include_color_table=True, disposal=1,
                                            transparency=self.TRANSPARENT):
            self.fp.write(chunk)
        self._previous = frame.copy()
        self.count += 1

    def close(self) -> None:
        self.fp.write(b";")  # GIF trailer


class VideoWriter:
    """Stream frames into a ``.gif`` or ``.mp4`` file (memory flat in the number of frames).

    ::

        with VideoWriter("episode.gif", fps=15) as video:
            for frame in frames:
                video.add(frame)

    Args:
        path: output file; the suffix picks the format (``.mp4`` needs ``imageio-ffmpeg``).
        fps: playback rate (frames per second, > 0).

    Frames are ``(H, W, 3)`` arrays of one shape (other dtypes are clipped to uint8). The file
    appears at ``path`` only when the block ends without an error (``close()``); on an error no
    partial file is left (``abort()``).
    """

    def __init__(self, path: str | os.PathLike, fps: float = 20) -> None:
        self.path = Path(path)
        self.suffix = _check_video_args(self.path, fps)
        self.fps = fps
        self.frames = 0
        self._shape: tuple[int, ...] | None = None
        self._context: contextlib.AbstractContextManager | None = None
        self._fp: IO[bytes] | None = None
        self._encoder: Any = None
        self._tmp: Path | None = None

    def add(self, frame: np.ndarray) -> None:
        arr = np.asarray(frame)
        if self._shape is None:
            _check_frames("VideoWriter", [arr])
            self._shape = arr.shape
            self._open()
        elif arr.shape != self._shape:
            raise ValueError(f"VideoWriter: frame {self.frames} has shape {arr.shape}; frame 0 has {self._shape}")
        arr = arr if arr.dtype == np.uint8 else np.clip(arr, 0, 255).astype(np.uint8)
        if self.suffix == ".gif":
            self._encoder.add(arr)
        else:
            h, w = arr.shape[:2]
            if h % 2 or w % 2:     # H.264 in yuv420p needs even sizes: pad by repeating the edge
                arr = np.pad(arr, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
            self._encoder.append_data(arr)
        self.frames += 1

    def _open(self) -> None:
        self._context = _replacing(self.path)
        tmp = self._tmp = self._context.__enter__()
        try:
            if self.suffix == ".gif":
                self._fp = open(tmp, "wb")
                self._encoder = _GifStream(self._fp, self.fps)
            else:
                import imageio.v2 as imageio

                self._encoder = imageio.get_writer(tmp, format="FFMPEG", fps=self.fps, macro_block_size=1)
        except BaseException:
            self.abort()
            raise

    def close(self) -> Path:
        """Finish the file and move it to ``path``; ValueError if no frame was added."""
        if self._context is None:
            raise ValueError("VideoWriter: no frames; allowed: one or more frames")
        try:
            if self.suffix == ".gif":
                self._encoder.close()
                self._fp.close()
            else:
                self._encoder.close()
        except BaseException as err:
            self.abort(err)
            named = _naming(err, self.path, self._tmp)
            if named is not err:
                raise named from None
            raise
        context, self._context = self._context, None
        context.__exit__(None, None, None)
        return self.path

    def abort(self, err: BaseException | None = None) -> None:
        """Drop the partial file (after an error)."""
        for closing in (self._fp, self._encoder if self.suffix == ".mp4" else None):
            if closing is not None:
                with contextlib.suppress(Exception):
                    closing.close()
        context, self._context = self._context, None
        if context is not None:
            error = err if err is not None else RuntimeError("aborted")
            with contextlib.suppress(BaseException):
                context.__exit__(type(error), error, None)

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, kind, error, tb) -> None:
        if kind is None:
            self.close()
            return
        self.abort(error)
        named = _naming(error, self.path, self._tmp)
        if named is not error:
            raise named from None


def save_video(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: int = 20) -> Path:
    """Write frames to a ``.gif`` (Pillow) or ``.mp4`` (needs ``imageio-ffmpeg``) via ``VideoWriter``.

    Args:
        frames: equally shaped ``(H, W, 3)`` uint8 arrays, e.g. from ``Renderer.render`` (any
            iterable: a generator is streamed).
        path: output file; the suffix picks the format. Parent folders are created.
        fps: playback rate (frames per second, > 0).

    Returns:
        The path written.

    Raises:
        ValueError: no frames, frames of different or wrong shapes, a bad ``fps``, an
            unsupported suffix, or ``.mp4`` without ``imageio-ffmpeg`` (``pip install imageio-ffmpeg``).
    """
    path = Path(path)
    _check_video_args(path, fps)
    if isinstance(frames, (list, tuple)):
        _check_frames("save_video", frames)  # every frame checked before a file is opened
    with VideoWriter(path, fps) as video:
        for frame in frames:
            video.add(frame)
        if video.frames == 0:
            raise ValueError("save_video: no frames; allowed: one or more frames")
    return path
