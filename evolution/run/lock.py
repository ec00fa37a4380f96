"""One writer per run directory: an advisory lock on ``RUN_DIR/.lock``.

``RunLock`` is an ``fcntl.flock`` on the lock file, which also holds the writer's PID. The
kernel releases a flock when its holder dies, however it dies, so a lock left by a killed
run is free; the PID it left tells who held it (the next writer says it took it over).
"""

from __future__ import annotations

import fcntl
import os
import time
import warnings
from pathlib import Path

from evolution.guard import UsageError

LOCK_FILE = ".lock"
"""The run directory's lock file (``RunLock``)."""

_HELD_LOCKS: set[int] = set()


def drop_inherited_locks() -> None:
    """In a forked child (a process-pool worker): close the copies of the parent's lock files.

    The parent's lock stays in place, and a SIGKILLed trainer's lock is free at once instead
    of when its last worker exits.
    """
    for fd in list(_HELD_LOCKS):
        try:
            os.close(fd)
        except OSError:
            pass
    _HELD_LOCKS.clear()


class RunLock:
    """The advisory lock of one run directory (``fcntl.flock`` on ``RUN_DIR/.lock``).

    ``acquire()`` takes it (creating the folder and the lock file) and records this PID in the
    file; ``acquire(create=False)`` takes it only if the lock file exists (a run directory
    without one has no writer, and nothing is written into it this way). A lock held by a
    living process raises ``UsageError`` naming the directory and its PID; a lock left by a
    dead process is free (the kernel released it) and is taken over with a warning.
    ``check()`` raises if the run directory was deleted or replaced under the holder.
    """

    def __init__(self, run_dir: Path, what: str = "run directory", by: str = "a gathering-evolve run") -> None:
        self.run_dir = Path(run_dir)
        self.what, self.by = what, by  # for the refusal: "<dir>: <what> is in use by process N (<by>)"
        self.path = self.run_dir / LOCK_FILE
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self, create: bool = True) -> None:
        if self._fd is not None:
            return
        if create:
            self.run_dir.mkdir(parents=True, exist_ok=True)
        elif not self.path.is_file():
            return
        try:
            fd = os.open(self.path, os.O_RDWR | (os.O_CREAT if create else 0), 0o644)
        except (PermissionError, FileNotFoundError):
            if create:
                raise
            return  # a lock file this user cannot write: the first write will say what is wrong
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read_pid(fd)
            for _ in range(10):  # the holder writes its PID just after taking the lock
                if holder:
                    break
                time.sleep(0.05)
                holder = _read_pid(fd)
            os.close(fd)
            who = f"process {holder}" if holder else "another process"
            raise UsageError(f"{self.run_dir}: {self.what} is in use by {who} ({self.by}); "
                             f"allowed: one writer per {self.what}: wait for it to end, or choose another "
                             "--out") from None
        except BaseException:
            os.close(fd)
            raise
        previous = _read_pid(fd)
        if previous and previous != os.getpid():
            warnings.warn(f"{self.path}: lock of process {previous}, which is no longer running, taken over",
                          stacklevel=2)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd
        _HELD_LOCKS.add(fd)

    def check(self) -> None:
        """Raise ``OSError`` naming the folder if the run directory is no longer the one locked."""
        if self._fd is None:
            return
        mine = os.fstat(self._fd)
        try:
            now = os.stat(self.path)
        except FileNotFoundError:
            now = None
        if now is None or (now.st_ino, now.st_dev) != (mine.st_ino, mine.st_dev):
            raise FileNotFoundError(2, "run directory was deleted or replaced while the run was writing it",
                                    str(self.run_dir))

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is None:
            return
        _HELD_LOCKS.discard(fd)
        try:
            os.ftruncate(fd, 0)  # a clean end leaves no PID behind (no "taken over" note next time)
        except OSError:
            pass
        os.close(fd)  # closing releases the flock

    def __enter__(self) -> RunLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _read_pid(fd: int) -> int | None:
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


__all__ = ["LOCK_FILE", "RunLock", "drop_inherited_locks"]
