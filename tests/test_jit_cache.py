"""numba's cache checks only a kernel's own file, so ``gathering_env.compiled`` drops it whenever
any source of the package changed (``refresh_jit_cache``): a constant edited in another module
reaches the compiled kernels too."""

from __future__ import annotations

from pathlib import Path

from gathering_env.compiled import STAMP, refresh_jit_cache


def _cache_files(cache: Path) -> list[str]:
    for name in ("kernels.sense-10.py311.nbi", "kernels.sense-10.py311.1.nbc"):
        (cache / name).write_bytes(b"machine code")
    return sorted(p.name for p in cache.glob("*.nb?"))


def test_the_cache_is_dropped_when_any_source_changes_and_kept_otherwise(tmp_path):
    package, cache = tmp_path / "pkg", tmp_path / "pkg" / "compiled" / "__pycache__"
    (package / "compiled").mkdir(parents=True)
    (package / "drive.py").write_text("WHEEL_FORCE = 2.5\n")
    (package / "compiled" / "kernels.py").write_text("from ..drive import WHEEL_FORCE\n")
    assert refresh_jit_cache(package, cache)                 # no stamp yet: dropped, stamped
    assert (cache / STAMP).is_file()
    assert len(_cache_files(cache)) == 2
    assert not refresh_jit_cache(package, cache)             # nothing changed: kept
    assert len(list(cache.glob("*.nb?"))) == 2
    (package / "drive.py").write_text("WHEEL_FORCE = 1.0\n")  # a constant in another module
    assert refresh_jit_cache(package, cache)
    assert list(cache.glob("*.nb?")) == []
    _cache_files(cache)
    (package / "extra.py").write_text("")                    # a new source file counts too
    assert refresh_jit_cache(package, cache)
    assert list(cache.glob("*.nb?")) == []
    (cache / "other.txt").write_text("kept")                 # only numba's files are removed
    (package / "extra.py").write_text("x = 1\n")
    refresh_jit_cache(package, cache)
    assert (cache / "other.txt").read_text() == "kept"


def test_a_folder_that_cannot_be_written_is_left_alone(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "a.py").write_text("")
    blocked = tmp_path / "file-not-folder"
    blocked.write_text("")
    assert not refresh_jit_cache(package, blocked / "__pycache__")
