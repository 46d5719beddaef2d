"""numba set-up of the engine: where compiled code is cached, and the compile notice.

Imported by ``rockfall_design.engine`` before anything imports numba, because
numba reads ``NUMBA_CACHE_DIR`` when it is imported.

Where the cache goes, in order:

1. ``NUMBA_CACHE_DIR`` if the user set it (numba's own setting);
2. ``__pycache__`` beside the engine's sources, numba's default, if writable;
3. ``<system temp dir>/rockfall-design-numba-<uid>``, private to the user,
   when the package directory is read-only (a system-wide install, a
   container image); numba would otherwise try the user's home and, if that
   is read-only too, refuse to import the engine;
4. no cache at all, with a one-line notice: every run compiles anew.

Wherever it is, a cache compiled from other engine sources than the ones
installed is removed first (:func:`drop_stale_cache`).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

PROG = "rockfall-design"
COMPILE_ESTIMATE = "about 20 to 60 s"
"""What the first compilation takes (measured 20 to 40 s on one core of a laptop-class CPU)."""


def _writable_dir(path: Path) -> bool:
    """True if ``path`` is (or can be made) a directory this process can write into.

    Tried by writing, not by permission bits: root passes every permission
    check but not a read-only file system, and a path under a file fails for all.
    """
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError:
        return False
    return True


def _private_dir(path: Path) -> bool:
    """True if ``path`` can be used as a private cache: ours, not writable by others.

    numba's cache holds pickles that it loads, so a directory in a shared temp
    dir that someone else created (or can write into) must not be used.
    """
    try:
        path.mkdir(mode=0o700, parents=False, exist_ok=True)
        st = path.stat()
    except OSError:
        return False
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        return False
    if st.st_mode & 0o022:
        return False
    return _writable_dir(path)


def choose_cache_dir(
    env: dict[str, str] | os._Environ[str],
    package_dir: Path,
    temp_dir: Path,
) -> tuple[str | None, bool]:
    """Decide where numba caches the engine.

    Parameters
    ----------
    env : mapping
        The environment (``NUMBA_CACHE_DIR`` is honoured if set).
    package_dir : Path
        The engine's source directory (numba's default cache is its ``__pycache__``).
    temp_dir : Path
        The system's temporary directory.

    Returns
    -------
    cache_dir : str or None
        A directory to give numba as ``NUMBA_CACHE_DIR``, or None to leave
        numba's own choice (the user's setting, or the package's ``__pycache__``).
    enabled : bool
        False if no directory can hold the cache.
    """
    if env.get("NUMBA_CACHE_DIR"):
        return None, True
    if _writable_dir(package_dir / "__pycache__"):
        return None, True
    uid = os.getuid() if hasattr(os, "getuid") else 0
    private = temp_dir / f"rockfall-design-numba-{uid}"
    if _private_dir(private):
        return str(private), True
    return None, False


def _configure() -> bool:
    cache_dir, enabled = choose_cache_dir(
        os.environ, Path(__file__).resolve().parent, Path(tempfile.gettempdir())
    )
    if cache_dir is not None:
        if "numba" in sys.modules:
            # Imported before us: its locators read the setting at decoration time.
            import numba

            numba.config.CACHE_DIR = cache_dir
        else:
            os.environ["NUMBA_CACHE_DIR"] = cache_dir
    return enabled


CACHE: bool = _configure()
"""Whether the engine's compiled functions are cached on disk (``cache=`` of ``njit``)."""


def hot(fn: Callable[..., Any]) -> Any:
    """Compile ``fn``, a function of the rock's event loop, without reference counting.

    numba counts references to every array a compiled function is handed:
    an atomic increment and decrement per array and call, which its pruning
    pass removes only within simple control flow. In the event loop, whose
    functions take the ground, the material table, the random stream and
    the output rows, that was about 38 % of the engine's time (measured with
    ``perf`` on ``projects/benchmark.yaml``, one thread), and the atomics on
    arrays that the threads of one run share make the cores wait on each
    other. A function compiled this way (numba's ``_nrt=False``) neither
    counts references nor may allocate: it only reads and writes arrays that
    its caller holds (the batch, :func:`~.ensemble._run_batch`, which
    allocates every array, scratch included, and keeps them alive). numba
    refuses to compile an allocation in it, so the rule cannot be broken
    silently. Results are bit-identical (``benchmarks/golden.py``).
    """
    from numba import njit

    return njit(cache=CACHE, _nrt=False)(fn)

_notice_lock = threading.Lock()
_checked: set[int] = set()


def will_compile(dispatcher: Any, args: Sequence[Any]) -> bool:
    """True if calling ``dispatcher`` with ``args`` compiles (neither in memory nor cached).

    Uses numba's cache index as numba itself reads it; if that ever fails (a
    numba that keeps it otherwise) the answer is False, and the only loss is
    the notice.
    """
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if any(tuple(s) == sig for s in dispatcher.overloads):
            return False
        cache = dispatcher._cache
        if not CACHE or not getattr(cache, "_enabled", False):
            return True
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key not in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - the notice must never break a run
        return False


def compile_notice(dispatcher: Any, args: Sequence[Any]) -> Callable[[], None] | None:
    """Say on stderr, once per function and process, that it is being compiled.

    Returns a callable to call once the first call has returned (it reports
    how long compiling took), or None if nothing is compiled.
    """
    with _notice_lock:
        if id(dispatcher) in _checked:
            return None
        _checked.add(id(dispatcher))
    if not will_compile(dispatcher, args):
        return None
    where = (
        "it is cached for later runs"
        if CACHE
        else "no writable directory for numba's cache, so every run compiles it"
    )
    sys.stderr.write(
        f"{PROG}: compiling the trajectory engine for this machine "
        f"({COMPILE_ESTIMATE}; {where})...\n"
    )
    sys.stderr.flush()
    t0 = time.perf_counter()

    def done() -> None:
        sys.stderr.write(f"{PROG}: engine compiled in {time.perf_counter() - t0:.0f} s\n")
        sys.stderr.flush()

    return done


SOURCES_MARK = "rockfall-design-engine.sha256"
"""File beside numba's cache files holding the digest of the sources they were compiled from."""


def sources_digest(sources_dir: Path) -> str:
    """SHA-256 of every ``*.py`` file of ``sources_dir`` (names and contents, sorted)."""
    h = hashlib.sha256()
    for path in sorted(sources_dir.glob("*.py")):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def drop_stale_cache(dispatcher: Any, sources_dir: Path) -> int:
    """Delete the engine's cached machine code if any engine source changed since it was cached.

    numba knows a cached function by its own file only: a function whose
    callees live in other files (the rock's event loop calls the impact,
    contact, flight and barrier modules; the batch kernel calls the event
    loop) would keep running the old callees after one of those files
    changed. So the digest of all the engine's sources is kept beside the
    cache, and a cache built from other sources is removed before anything
    loads from it: the next call compiles afresh.

    Parameters
    ----------
    dispatcher : numba dispatcher
        Any compiled function of the engine (they share one cache directory).
    sources_dir : Path
        The engine's source directory.

    Returns
    -------
    int
        Number of cache files removed. Never raises: at worst the check is
        skipped, as numba's own behaviour was.
    """
    try:
        cache = getattr(dispatcher, "_cache", None)
        if not CACHE or cache is None or not getattr(cache, "_enabled", False):
            return 0
        where = Path(cache._cache_path)
        digest = sources_digest(sources_dir)
        mark = where / SOURCES_MARK
        if mark.is_file() and mark.read_text().strip() == digest:
            return 0
        stems = {p.stem for p in sources_dir.glob("*.py")}
        removed = 0
        if where.is_dir():
            for f in where.iterdir():
                if f.suffix in (".nbi", ".nbc") and f.name.split(".", 1)[0] in stems:
                    with contextlib.suppress(FileNotFoundError):
                        f.unlink()
                        removed += 1
        where.mkdir(parents=True, exist_ok=True)
        # Written whole, then renamed: a process starting at the same time
        # reads the old mark or the new one, never half of one.
        tmp = where / f".{SOURCES_MARK}.{os.getpid()}"
        tmp.write_text(digest + "\n")
        os.replace(tmp, mark)
        return removed
    except Exception:  # noqa: BLE001 - the check must never break an import
        return 0
