"""Stopping a run cleanly: the first SIGINT, SIGTERM or SIGHUP asks, a second one insists.

``StopSignals`` is the trainer's handler for the length of a run (``with StopSignals(...) as
stop``): the first signal sets ``stop.requested`` and prints that the generation in flight will
finish (its statistics and checkpoint written) before the run stops; a second one raises
``KeyboardInterrupt`` to abandon that generation at once. Either way the run resumes from its
last checkpoint. SIGHUP is the terminal closing. Outside the main thread (a run started from a
worker thread) Python cannot install handlers, and none are.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class StopSignals:
    """Install the handlers on entry and put the previous ones back on exit.

    Args:
        generation: called when a signal arrives, for the message (the generation in flight).
    """

    def __init__(self, generation: Callable[[], int]) -> None:
        self.generation = generation
        self.requested = False
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt  # second signal: abandon the generation in flight
        self.requested = True
        print(f"\nsignal {signum}: finishing generation {self.generation()}, then stopping "
              "(again to abandon it); resume with --resume", flush=True)

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: Any) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()
