"""The production step: numba kernels (``kernels``) and the W-world engine around pymunk (``engine``).

Every part of a step but pymunk's own calls runs here, compiled; ``gathering_env.reference``
computes the same step in plain numpy, and the tests hold the two to identical episodes.

numba's on-disk cache (``cache=True``) checks only each kernel's own file: a constant a kernel
imports from another module (``gathering_env.drive``'s forces, ``gathering_env.khepera``'s curve,
``tables``' flags) is frozen into the cached machine code, so after an edit there the compiled
kernel would go on with the old value while the numpy one takes the new. ``refresh_jit_cache``
therefore drops the cache in this folder's ``__pycache__`` whenever any source of the package
changed since the cache was written (before the kernels are imported). A cache moved elsewhere
with ``NUMBA_CACHE_DIR`` is not reached: clear that one yourself after such an edit.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

STAMP = "gathering-sources.sha256"
"""The file in the cache folder that holds the fingerprint of the sources the cache was built from."""


def refresh_jit_cache(package: Path, cache: Path) -> bool:
    """Delete numba's cache files (``*.nbi``, ``*.nbc``) in ``cache`` unless the fingerprint of
    every ``*.py`` under ``package`` equals the one stamped there; then stamp the current one.
    Returns whether the cache was dropped. A folder that cannot be written (a read-only install,
    whose sources cannot change under it) is left as it is."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    fingerprint = digest.hexdigest()
    stamp = cache / STAMP
    try:
        if stamp.read_text() == fingerprint:
            return False
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for stale in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
            stale.unlink(missing_ok=True)
        stamp.write_text(fingerprint)
    except OSError:
        return False
    return True


refresh_jit_cache(Path(__file__).resolve().parent.parent, Path(__file__).resolve().parent / "__pycache__")
