"""Crash-safe checkpoints of a run: atomic writes, a format version and a checksum.

File layout: one header line ``GATHERING-CHECKPOINT <version> <sha256 of payload>\\n``
followed by the gzip-compressed pickle payload. A checkpoint is written to a temporary
file in the same directory, flushed, fsync'ed and renamed over the target, so a killed
process leaves either the old or the new checkpoint, never a torn one.

Checkpoints are pickles: load only checkpoints you (or someone you trust) wrote.
Champions and fronts use the safe JSON format of ``evolution.run.champion``.
"""

from __future__ import annotations

import gzip
import hashlib
import os
import pickle
import tempfile
from pathlib import Path
from typing import Any

from evolution.guard import writing

MAGIC = b"GATHERING-CHECKPOINT"
VERSION = 1


class CheckpointError(ValueError):
    """A checkpoint that is missing, truncated, corrupt or of another version."""


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file + fsync + rename)."""
    path = Path(path)
    with writing(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual file permissions
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except BaseException:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
            raise


def save_checkpoint(path: Path, state: dict[str, Any]) -> None:
    """Pickle ``state`` into a versioned, checksummed checkpoint file (atomically)."""
    payload = gzip.compress(pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL), compresslevel=5, mtime=0)
    digest = hashlib.sha256(payload).hexdigest().encode()
    atomic_write_bytes(path, MAGIC + b" " + str(VERSION).encode() + b" " + digest + b"\n" + payload)


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Read a checkpoint written by ``save_checkpoint``.

    Raises:
        CheckpointError: naming the file and what is wrong (missing, not a checkpoint,
            other version, truncated/corrupt payload).
    """
    path = Path(path)
    if path.is_dir():
        raise CheckpointError(f"{path}: is a folder; allowed: a checkpoint file (RUN_DIR/checkpoints/gen-NNNN.ckpt)")
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        raise CheckpointError(f"{path}: checkpoint not found") from None
    header, sep, payload = blob.partition(b"\n")
    parts = header.split(b" ")
    if not sep or len(parts) != 3 or parts[0] != MAGIC:
        raise CheckpointError(f"{path}: not a gathering checkpoint (bad header)")
    try:
        version = int(parts[1])
    except ValueError:
        raise CheckpointError(f"{path}: bad checkpoint version field {parts[1]!r}") from None
    if version != VERSION:
        raise CheckpointError(f"{path}: checkpoint version {version}; this package reads version {VERSION}")
    if hashlib.sha256(payload).hexdigest().encode() != parts[2]:
        raise CheckpointError(f"{path}: checkpoint is truncated or corrupt (checksum mismatch)")
    try:
        state = pickle.loads(gzip.decompress(payload))
    except Exception as err:  # noqa: BLE001 - any unpickling failure means a broken file
        raise CheckpointError(f"{path}: checkpoint payload unreadable: {err}") from None
    if not isinstance(state, dict):
        raise CheckpointError(f"{path}: checkpoint payload is not a state dict")
    return state
