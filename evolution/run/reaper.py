"""Ray's processes die with the trainer that started them, even when it is SIGKILLed.

A trainer that starts a local Ray (``evolution.run.backends.RayEvaluator``) shuts it down on
every exit it can catch (``close()`` in a ``finally``; SIGINT/SIGTERM/SIGHUP end the run
normally). A SIGKILL cannot be caught: Ray's GCS server and raylet are re-parented to init
and its agents and workers live on. So the trainer also starts this reaper, a small process
of its own session that every ``POLL_SECONDS`` notes the trainer's descendants (by PID and
start time, so a reused PID is never hit) and, once the trainer is gone, sends SIGTERM to the
ones still alive (and to any children they started since), then SIGKILL to the rest after
``GRACE_SECONDS``. ``RayEvaluator.close()`` stops the reaper after ``ray.shutdown()``.

Linux only (it reads ``/proc``); elsewhere ``start_reaper`` returns None.

Usage (internal): ``python evolution/run/reaper.py TRAINER_PID TRAINER_START_TIME``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections import defaultdict

POLL_SECONDS = 0.2
GRACE_SECONDS = 3.0


def _stat(pid: int) -> tuple[int, int] | None:
    """(parent PID, start time in clock ticks) of a living process, None if gone or a zombie."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "; comm may hold spaces
    if fields[0] in ("Z", "X"):
        return None
    return int(fields[1]), int(fields[19])


def process_table() -> dict[int, tuple[int, int]]:
    """Every living process: PID -> (parent PID, start time)."""
    table = {}
    for name in os.listdir("/proc"):
        if name.isdigit() and (entry := _stat(int(name))) is not None:
            table[int(name)] = entry
    return table


def descendants(roots: set[int], table: dict[int, tuple[int, int]]) -> dict[int, int]:
    """PID -> start time of every descendant of ``roots`` (the roots excluded)."""
    children: dict[int, list[int]] = defaultdict(list)
    for pid, (ppid, _) in table.items():
        children[ppid].append(pid)
    found: dict[int, int] = {}
    stack = list(roots)
    while stack:
        for child in children.get(stack.pop(), ()):
            if child not in found and child not in roots:
                found[child] = table[child][1]
                stack.append(child)
    return found


def start_time(pid: int) -> int | None:
    entry = _stat(pid)
    return None if entry is None else entry[1]


def _alive(known: dict[int, int], table: dict[int, tuple[int, int]]) -> dict[int, int]:
    alive = {pid: start for pid, start in known.items() if table.get(pid, (0, None))[1] == start}
    alive.update(descendants(set(alive), table))  # children they started meanwhile
    alive.pop(os.getpid(), None)
    return alive


def reap(known: dict[int, int], grace: float = GRACE_SECONDS) -> None:
    """SIGTERM the processes of ``known`` still alive (and their children), SIGKILL them after ``grace``."""
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, 1.0)):
        targets = _alive(known, process_table())
        for pid in targets:
            try:
                os.kill(pid, sig)
            except OSError:
                pass
        known.update(targets)
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline and _alive(known, process_table()):
            time.sleep(0.05)


def watch(trainer: int, trainer_start: int) -> None:
    """Note the trainer's descendants until it is gone, then reap them."""
    me = os.getpid()
    known: dict[int, int] = {}
    while True:
        table = process_table()
        if table.get(trainer, (0, None))[1] != trainer_start:
            break
        found = descendants({trainer}, table)
        found.pop(me, None)
        known.update(found)
        time.sleep(POLL_SECONDS)
    reap(known)


def start_reaper() -> subprocess.Popen | None:
    """Start the reaper of this process's descendants (None where there is no ``/proc``)."""
    me = os.getpid()
    start = start_time(me) if os.path.isdir("/proc/self") else None
    if start is None:
        return None
    return subprocess.Popen([sys.executable, os.path.abspath(__file__), str(me), str(start)],  # stdlib only
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)  # Ctrl-C in the terminal is the trainer's to handle


def stop_reaper(reaper: subprocess.Popen | None) -> None:
    if reaper is not None and reaper.poll() is None:
        reaper.terminate()
        try:
            reaper.wait(timeout=5)
        except subprocess.TimeoutExpired:
            reaper.kill()
            reaper.wait()


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    watch(int(sys.argv[1]), int(sys.argv[2]))
