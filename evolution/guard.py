"""What every command shares to fail safely: one error format, one output-folder rule.

* ``UsageError`` (a ``ValueError``): a problem the user can fix; its message is
  ``<path or option>: <what is wrong>; <what is allowed>``.
* ``@command``: wraps a ``main(argv) -> int``. A ``ValueError`` (``UsageError``,
  ``ExperimentError``, ``CheckpointError``, ``ChampionError``, ...) or an ``OSError`` ends as
  one line ``error: ...`` on stderr and exit status 2; warnings are printed as one line
  ``warning: ...``; Ctrl-C ends with status 130.
* ``ArgumentParser``: argparse with the same one-line ``error:`` format (status 2).
* ``int_arg(low, high)``: an argparse type for a bounded integer option.
* ``check_output_dir``/``check_output_file``: commands write only into a missing or empty
  folder, or one that holds nothing but their own earlier output; they never delete a file.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import functools
import math
import os
import re
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path


class UsageError(ValueError):
    """Bad input the user can fix: ``<path or option>: <what is wrong>; <what is allowed>``."""


def one_line(message: str) -> str:
    return " ".join(part.strip() for part in str(message).splitlines() if part.strip())


def fail(message: str) -> int:
    print(f"error: {one_line(message)}", file=sys.stderr)
    return 2


def describe_os_error(err: OSError) -> str:
    """``<file>: <reason>; allowed: ...`` (writes go through ``writing(path)``, so the file is known)."""
    where = err.filename if err.filename is not None else "file system (file unknown)"
    reason = (err.strerror or str(err) or type(err).__name__).lower()
    if err.errno in (errno.ENOSPC, errno.EDQUOT):
        allowed = "free space on that disk (or another --out)"
    elif err.errno == errno.EFBIG:
        allowed = "a file size within the limit (ulimit -f) or another location"
    else:
        allowed = "a path you can read and write (check it and its permissions)"
    return f"{where}: {reason}; allowed: {allowed}"


@contextlib.contextmanager
def writing(path: Path | str) -> Iterator[None]:
    """An ``OSError`` raised inside (a full disk, a file too large) names ``path`` if it named no file.

    ``write()``, ``flush()``, ``fsync()`` and ``close()`` errors carry no file name of their own.
    """
    try:
        yield
    except OSError as err:
        if err.filename is not None:
            raise
        raise OSError(err.errno, err.strerror or str(err) or type(err).__name__, str(path)) from None


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    print(f"warning: {one_line(str(message))}", file=sys.stderr)


def command(main: Callable[[list[str] | None], int]) -> Callable[[list[str] | None], int]:
    """Run a CLI ``main`` so that no user error ends in a traceback (see the module docstring)."""

    @functools.wraps(main)
    def wrapper(argv: list[str] | None = None) -> int:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            try:
                return main(argv)
            except KeyboardInterrupt:
                print("\ninterrupted", file=sys.stderr)
                return 130
            except ValueError as err:
                return fail(str(err))
            except BrokenPipeError:
                # The reader went away (``gathering-evolve --list | head -1``): stop quietly, as
                # Python's docs advise; point stdout at devnull so the exit flush cannot fail too.
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
                return 1
            except OSError as err:
                return fail(describe_os_error(err))
            except MemoryError:
                return fail("out of memory; allowed: smaller sizes (population, robots, steps, workers)")

    return wrapper


class ArgumentParser(argparse.ArgumentParser):
    """argparse, but a bad option prints one line ``error: ...`` (exit status 2)."""

    def error(self, message: str):  # type: ignore[override]
        choice = re.fullmatch(r"argument (\S+): invalid choice: (.+) \(choose from (.+)\)", message)
        if choice:
            message = f"{choice[1]}: {choice[2]} is not a choice; allowed: {choice[3]}"
        fail(f"{message}; see {self.prog} --help")
        sys.exit(2)


def int_arg(low: int, high: float) -> Callable[[str], int]:
    """argparse type: an integer in [low, high]."""

    allowed = f"an integer >= {low}" if high == float("inf") else f"{low}..{high}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer; allowed: {allowed}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is out of range; allowed: {allowed}")
        return value

    parse.__name__ = "integer"
    return parse


def float_arg(low: float, high: float = float("inf"), *, open_low: bool = False) -> Callable[[str], float]:
    """argparse type: a finite number in [low, high] (``open_low``: in (low, high])."""

    allowed = f"a number {'>' if open_low else '>='} {low}" + (f" and <= {high}" if high != float("inf") else "")

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number; allowed: {allowed}") from None
        if not math.isfinite(value) or value < low or (open_low and value == low) or value > high:
            raise argparse.ArgumentTypeError(f"{text} is out of range; allowed: {allowed}")
        return value

    parse.__name__ = "number"
    return parse


def world_setting(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` of a ``--world`` option: VALUE read as a TOML value (numbers, booleans, arrays,
    quoted strings), else taken as a bare string (``weld_spin=free``)."""
    import tomllib

    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key.isidentifier() or "\n" in value or "\r" in value:
        raise argparse.ArgumentTypeError(f"{text!r} is not KEY=VALUE (a world parameter and its value, on one line)")
    try:
        return key, tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        return key, value.strip()


#: World keys that commands set with options of their own (then ``--world`` may not).
OWN_OPTIONS = {"environment": "--environment", "max_cycles": "--steps", "num_robots": "--robots"}


def with_world_settings(env_config: dict, settings: list[tuple[str, object]], own: Iterable[str]) -> dict:
    """``env_config`` with the ``--world`` settings over it, checked as a whole by ``WorldConfig``:
    an unknown key, a refused value or a key of one of the command's own options (``own``, a
    subset of ``OWN_OPTIONS``) is a ``UsageError`` naming the settings."""
    from gathering_env import WorldConfig

    for key, _ in settings:
        if key in own:
            raise UsageError(f"--world {key}: the command's option {OWN_OPTIONS[key]} sets it; allowed: that option")
    changed = {**env_config, **dict(settings)}
    try:
        WorldConfig.from_kwargs(**changed)
    except (TypeError, ValueError) as e:
        raise UsageError(f"--world {' '.join(f'{k}={v!r}' for k, v in settings)}: {e}") from None
    return changed


def _check_creatable(path: Path, what: str) -> None:
    """``path`` does not exist: its nearest existing ancestor must be a writable folder."""
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise UsageError(f"{what} {path}: {parent} is a file, not a folder; allowed: a path under a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"{what} {path}: folder {parent} is not writable; allowed: a writable location")


def check_output_dir(path: Path, owned: Iterable[str] = (), what: str = "--out", hint: str = "") -> None:
    """Refuse an output folder that holds anything but this command's own earlier output.

    Allowed: a missing folder (under a writable one), an empty folder, or a folder whose
    entries all have names in ``owned`` (files the command writes and may overwrite).
    ``hint``: appended to the refusal (e.g. how to continue a run instead).
    """
    path = Path(path)
    if not path.exists():
        _check_creatable(path, what)
        return
    if not path.is_dir():
        raise UsageError(f"{what} {path}: is a file; allowed: a missing or empty folder")
    owned = set(owned)
    foreign = sorted(p.name for p in path.iterdir() if p.name not in owned or not p.is_file())
    if foreign:
        shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more" if len(foreign) > 5 else "")
        allowed = "a missing or empty folder" + (f" or one holding only an earlier output ({', '.join(sorted(owned))})"
                                                 if owned else "")
        raise UsageError(f"{what} {path}: folder is not empty (holds {shown}); allowed: {allowed}"
                         + (f"; {hint}" if hint else ""))
    if not os.access(path, os.W_OK | os.X_OK):
        raise UsageError(f"{what} {path}: folder is not writable; allowed: a writable folder")


#: File signatures of the media the commands write: an existing file is overwritten only if
#: it already is such a file (an earlier output), never any other file.
SIGNATURES = {".gif": (0, (b"GIF87a", b"GIF89a")), ".png": (0, (b"\x89PNG\r\n\x1a\n",)), ".mp4": (4, (b"ftyp",))}


def check_output_file(path: Path, suffixes: Iterable[str], what: str = "--out") -> None:
    """Refuse an output file path unless it is new or an earlier output of the same kind.

    ``suffixes``: the allowed file kinds (keys of ``SIGNATURES``, e.g. ``(".gif", ".mp4")``).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    suffixes = tuple(suffixes)
    if suffix not in suffixes:
        raise UsageError(f"{what} {path}: suffix {suffix or '(none)'!r}; allowed: {', '.join(suffixes)}")
    if not path.exists():
        _check_creatable(path, what)
        return
    if not path.is_file():
        raise UsageError(f"{what} {path}: is a folder; allowed: a file name ending in {suffix}")
    offset, magics = SIGNATURES[suffix]
    with open(path, "rb") as f:
        head = f.read(offset + 8)[offset:]
    if not any(head.startswith(m) for m in magics):
        raise UsageError(f"{what} {path}: exists and is not a {suffix} file this command wrote; allowed: "
                         f"a new file name, or an earlier {suffix} output to replace")
    if not os.access(path, os.W_OK):
        raise UsageError(f"{what} {path}: file is not writable; allowed: a writable file")
