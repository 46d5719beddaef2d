"""numba set-up of the engine: where compiled code is cached, and the compile notice.

Imported by ``rockfall_design.engine`` before anything imports numba, because
numba reads ``NUMBA_CACHE_DIR`` when it is imported.

Where the cache goes, in order:

1. ``NUMBA_CACHE_DIR`` if the user set it (numba's own setting);
2. ``<user cache>/rockfall-design/engine-<digest>`` (``$XDG_CACHE_HOME``, else
   ``~/.cache``), private to the user and named by the digest of the
   engine's sources: one compile per machine and user, however the package
   is imported (an installed copy and a checkout of the same sources, as
   ``pip install .`` and then ``python -m pytest`` in the checkout, share it;
   numba's own default is a cache per copy, beside its sources);
3. ``__pycache__`` beside the engine's sources, numba's default, if writable;
4. ``<system temp dir>/rockfall-design-numba-<uid>``, private to the user,
   when the package directory is read-only (a system-wide install, a
   container image); numba would otherwise try the user's home and, if that
   is read-only too, refuse to import the engine;
5. no cache at all, with a one-line notice: every run compiles anew.

Wherever it is, a cache compiled from other engine sources than the ones
installed is removed first (:func:`drop_stale_cache`).
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

PROG = "rockfall-design"
COMPILE_ESTIMATE = "about 20 to 60 s"
"""What the first compilation takes (measured 20 to 40 s on one core of a laptop-class CPU)."""


SOURCES_MARK = "rockfall-design-engine.sha256"
"""File beside numba's cache files holding the digest of the sources they were compiled from."""


def sources_digest(sources_dir: Path) -> str:
    """SHA-256 of every ``*.py`` file of ``sources_dir`` (names and contents, sorted)."""
    h = hashlib.sha256()
    for path in sorted(sources_dir.glob("*.py")):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


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


ENGINE_DIR = Path(__file__).resolve().parent
"""The engine's source directory."""

KEEP_SHARED = 8
"""Caches of other engine sources kept beside the shared one (the most recently used;
any used in the last week is kept too)."""


def shared_cache_dir(env: dict[str, str] | os._Environ[str], sources_dir: Path,
                     home: Path) -> Path | None:
    """The user's cache for these engine sources, shared by every copy of them.

    Parameters
    ----------
    env : mapping
        The environment (``NUMBA_CACHE_DIR`` wins; ``XDG_CACHE_HOME`` is honoured).
    sources_dir : Path
        The engine's source directory; the cache is named by their digest.
    home : Path
        The user's home directory (``~/.cache`` when ``XDG_CACHE_HOME`` is unset).

    Returns
    -------
    Path or None
        ``<cache>/rockfall-design/engine-<16 hex digits>``, created private to
        the user; None if the user set ``NUMBA_CACHE_DIR`` or no such directory
        can be made (read-only home): then :func:`choose_cache_dir` decides.
    """
    if env.get("NUMBA_CACHE_DIR"):
        return None
    base = Path(env["XDG_CACHE_HOME"]) if env.get("XDG_CACHE_HOME") else home / ".cache"
    ours = base / "rockfall-design"
    try:
        ours.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError:
        return None
    path = ours / f"engine-{sources_digest(sources_dir)[:16]}"
    if not (_private_dir(ours) and _private_dir(path)):
        return None
    # Each change of the engine's sources (a developer's edits, an upgrade)
    # makes a new directory of about 3 MB: keep the latest few, and any used
    # in the last week (another copy of the package may be running from it).
    others = sorted((d for d in ours.glob("engine-*") if d != path and d.is_dir()),
                    key=lambda d: d.stat().st_mtime, reverse=True)
    week_ago = time.time() - 7 * 24 * 3600
    for old in others[KEEP_SHARED:]:
        if old.stat().st_mtime < week_ago:
            shutil.rmtree(old, ignore_errors=True)
    return path


def _share_cache(path: Path, digest: str) -> bool:
    """Have numba cache the engine's functions in ``path``, known by ``digest``.

    numba's locators place a cache by the source file's directory, so two
    copies of the same sources (an installed one and a checkout) compile
    twice. This locator, tried first and only for the engine's own files,
    places it in ``path`` and stamps it with the digest of all the engine's
    sources instead of one file's: a cache compiled from other sources is
    never loaded. numba's locators are not public API: if they change, the
    answer is False and numba's own choice applies (one compile per copy).
    """
    try:
        from numba.core import caching

        # Named with a leading underscore up to numba 0.6x, without it later.
        base = getattr(caching, "_CacheLocator", None) or caching.CacheLocator
        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl

        class _EngineLocator(base):
            def __init__(self, py_func: Any, py_file: str) -> None:
                self._lineno = py_func.__code__.co_firstlineno

            def get_cache_path(self) -> str:
                return str(path)

            def get_source_stamp(self) -> str:
                return digest

            def get_disambiguator(self) -> str:
                return str(self._lineno)

            @classmethod
            def from_function(cls, py_func: Any, py_file: str) -> Any:
                if Path(py_file).resolve().parent != ENGINE_DIR:
                    return None
                self = cls(py_func, py_file)
                try:
                    self.ensure_cache_path()
                except OSError:
                    return None
                return self

        impl._locator_classes.insert(0, _EngineLocator)
    except Exception:  # noqa: BLE001 - numba's default locators still work
        return False
    return True


def _configure() -> bool:
    try:
        home = Path.home()
    except (RuntimeError, KeyError):  # no HOME and no password entry
        home = Path(tempfile.gettempdir()) / "nonexistent-home"
    shared = shared_cache_dir(os.environ, ENGINE_DIR, home)
    if shared is not None and _share_cache(shared, sources_digest(ENGINE_DIR)):
        return True
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

DIGEST: str = sources_digest(ENGINE_DIR)
"""Digest of the engine's sources (what the kept machine code of ``native_code`` is checked by)."""


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

    optimise_once()
    return one_variant(njit(cache=CACHE, _nrt=False, no_cfunc_wrapper=True)(fn))


def compiled(fn: Callable[..., Any] | None = None, *, nogil: bool = False) -> Any:
    """Compile ``fn`` with numba (cached), one variant for every call from compiled code.

    ``@compiled`` or ``@compiled(nogil=True)``: numba's ``njit(cache=...)``,
    with :func:`one_variant`. Use it, not ``njit``, for every function of the
    engine.

    Neither this nor :func:`hot` has numba make a C-callable wrapper of the
    function (``no_cfunc_wrapper``), which only numba's first-class function
    types and ``cfunc`` use, and the engine neither: numba lowers one for
    every function it compiles, about a twentieth of the first compile
    (measured with ``py-spy`` on ``simulate projects/benchmark.yaml`` in an
    empty cache), with its machine code. The Python wrapper stays: the
    kernel is called from Python, and tests call the event loop's functions.
    """
    def wrap(f: Callable[..., Any]) -> Any:
        from numba import njit

        optimise_once()
        return one_variant(njit(cache=CACHE, nogil=nogil, no_cfunc_wrapper=True)(f))

    return wrap if fn is None else wrap(fn)


def writable(a: Any, dtype: Any = None) -> Any:
    """``a`` as a C-contiguous array numba types as writable (a copy only if it is not).

    numba compiles a function anew for each type of argument, and a
    read-only or strided array is a type of its own: the optimiser hands the
    engine its sections read-only (the plugin proxy's guard), and its first
    run after an install compiled a second variant of the kernel, about 30 s,
    for that alone. Arrays given to a compiled function from Python pass
    through here, so that one variant serves every caller. The engine never
    writes them; copying the few that are read-only costs microseconds.
    """
    out = np.ascontiguousarray(a, dtype=dtype)
    return out if out.flags.writeable else out.copy()


def one_variant(dispatcher: Any) -> Any:
    """Have ``dispatcher`` compile one variant per argument types, not one per constant.

    numba types a constant argument of a call between compiled functions as
    a literal (``Literal[int](0)``, ``Literal[bool](True)``) and compiles the
    callee for it, apart from the variant a variable argument gets: the
    engine compiled 14 of its functions twice so, among them the centre
    path's sweep (``profile.centre_path_of``, ``_visible_pieces``), about a
    fifth of the first compile (measured with numba's compile events). The
    callee is linked into its caller's module either way, where LLVM
    propagates the constant as it did; the machine code differs by branch
    layout at most, and the results not at all (``benchmarks/golden.py``).

    So the call is typed with plain types first (``numba.types.unliteral``);
    where the callee needs the literal (a tuple indexed by the argument,
    say), typing fails with plain types and the literal is used, as numba
    would. Not public numba API: if numba changes the method, its own
    behaviour applies and the only loss is the compile time.
    """
    try:
        from numba.core import errors, types

        base = type(dispatcher).get_call_template
    except (ImportError, AttributeError):  # pragma: no cover - numba changed
        return dispatcher

    def get_call_template(args: Sequence[Any], kws: dict[str, Any]) -> Any:
        await_helper(dispatcher)
        plain = tuple(types.unliteral(a) for a in args)
        plain_kws = {k: types.unliteral(v) for k, v in kws.items()}
        with as_callee():
            if plain != tuple(args) or plain_kws != kws:
                try:
                    return base(dispatcher, plain, plain_kws)
                except errors.TypingError:
                    pass
            return base(dispatcher, args, kws)

    try:
        dispatcher.get_call_template = get_call_template
    except AttributeError:  # pragma: no cover - a dispatcher without __dict__
        pass
    return dispatcher


_callee = threading.local()


@contextlib.contextmanager
def as_callee() -> Iterator[None]:
    """Within: what numba compiles is compiled for a compiled caller (see :func:`optimise_once`)."""
    _callee.depth = getattr(_callee, "depth", 0) + 1
    try:
        yield
    finally:
        _callee.depth -= 1


def optimise_once() -> bool:
    """Have LLVM's module passes run once on the kernel, not again on each function under it.

    numba optimises each compiled function's module with every callee
    linked in (its "cheap" and "full" module passes, at ``NUMBA_OPT``), then
    links that module into each caller and optimises the whole again: the
    event loop's code was optimised in the modules of ``simulate_rock``, of
    the kernel and of every function between, the centre path's sweep in
    four. A function compiled for a compiled caller (its typing calls it,
    :func:`one_variant`) now keeps its module as LLVM's function passes left
    it; the caller that Python calls (the kernel) runs the module passes on
    everything at once, where LLVM inlines and optimises the callees as it
    did. Results are bit-identical (no pass changes floating-point
    semantics: numba compiles without fast-math); the kernel's speed is
    measured in docs/speed.md. A callee later called from Python itself (a
    test calling ``impact``) runs its less optimised code.

    numba's ``CPUCodeLibrary`` is not public API: if it changes, nothing is
    patched and numba's own behaviour applies. ``ROCKFALL_DESIGN_OPTIMISE_ONCE=0``
    turns it off.

    Returns
    -------
    bool
        True if patched (now or before).
    """
    if os.environ.get("ROCKFALL_DESIGN_OPTIMISE_ONCE", "1") == "0":
        return False
    try:
        from numba.core import codegen

        cls = codegen.CPUCodeLibrary
        full = cls._optimize_final_module
    except (ImportError, AttributeError):  # pragma: no cover - numba changed
        return False
    if getattr(full, "_rockfall_design", False):
        return True

    def _optimize_final_module(self: Any) -> None:
        if getattr(_callee, "depth", 0) > 0:
            return
        full(self)

    _optimize_final_module._rockfall_design = True  # type: ignore[attr-defined]
    cls._optimize_final_module = _optimize_final_module
    return True


HELPER_TIMEOUT = 900.0
"""Longest wait (s) for a helper process's compile before compiling here instead."""

_helpers: dict[int, subprocess.Popen] = {}  # id(dispatcher) -> the helper compiling it
_helpers_lock = threading.Lock()


def compile_in_helper(dispatchers: Sequence[Any], code: str, payload: bytes) -> bool:
    """Have a second Python process compile ``dispatchers`` into the shared cache.

    numba compiles one function at a time in a process (a global lock), and
    the first compile of the engine is one thread's work; on a machine of
    two or more cores, a helper process compiles an independent part of the
    engine (the centre path's sweep, say) while this one compiles the rest.
    When this process's compile reaches a call of one of ``dispatchers``
    (its typing, :func:`one_variant`), it waits for the helper and loads the
    compiled function from the cache (numba reads its index anew each time):
    the machine code linked into the caller is the same as if this process
    had compiled it. If the helper fails, or takes over :data:`HELPER_TIMEOUT`,
    this process compiles the function itself, as before.

    Parameters
    ----------
    dispatchers : sequence of numba dispatchers
        What the helper compiles (each waited for on its first call).
    code : str
        The helper's program (``python -c``); it reads ``payload`` on stdin.
    payload : bytes
        Its input.

    Returns
    -------
    bool
        True if a helper was started. Not without a cache to share, on one
        core, or with ``ROCKFALL_DESIGN_COMPILE_HELPER=0``.
    """
    if not CACHE or os.environ.get("ROCKFALL_DESIGN_COMPILE_HELPER", "1") == "0":
        return False
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        cores = os.cpu_count() or 1
    if cores < 2:
        return False
    try:
        # Its own session: a Ctrl-C here does not print its traceback; it is
        # ended at exit if still running.
        proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
        assert proc.stdin is not None
        proc.stdin.write(payload)
        proc.stdin.close()
    except (OSError, ValueError):
        return False
    atexit.register(_end_helper, proc)
    with _helpers_lock:
        for d in dispatchers:
            _helpers[id(d)] = proc
    return True


def _end_helper(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.kill()
        with contextlib.suppress(OSError, subprocess.TimeoutExpired):
            proc.wait(5)


def await_helper(dispatcher: Any) -> None:
    """Wait for the helper compiling ``dispatcher``, if any (:func:`compile_in_helper`)."""
    with _helpers_lock:
        proc = _helpers.pop(id(dispatcher), None)
    if proc is None:
        return
    try:
        proc.wait(HELPER_TIMEOUT)
    except subprocess.TimeoutExpired:
        _end_helper(proc)


_notice_lock = threading.Lock()
_checked: set[tuple[int, tuple]] = set()


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
    """Say on stderr, once per function, argument types and process, that it is being compiled.

    Once per argument types, not per function: the optimiser runs the batch
    kernel with other arguments than ``simulate`` (resumed rocks, speeds
    recorded), and the first process after the engine changed compiled
    that variant too, some 30 s, without a word.

    Returns a callable to call once the first call has returned (it reports
    how long compiling took), or None if nothing is compiled.
    """
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
    except Exception:  # noqa: BLE001 - the notice must never break a run
        sig = ()
    with _notice_lock:
        if (id(dispatcher), sig) in _checked:
            return None
        first = not any(k[0] == id(dispatcher) for k in _checked)
        _checked.add((id(dispatcher), sig))
    if not will_compile(dispatcher, args):
        return None
    where = (
        "it is cached for later runs"
        if CACHE
        else "no writable directory for numba's cache, so every run compiles it"
    )
    what = "the trajectory engine" if first else "another variant of the trajectory engine"
    sys.stderr.write(
        f"{PROG}: compiling {what} for this machine "
        f"({COMPILE_ESTIMATE}; {where})...\n"
    )
    sys.stderr.flush()
    t0 = time.perf_counter()

    def done() -> None:
        sys.stderr.write(f"{PROG}: engine compiled in {time.perf_counter() - t0:.0f} s\n")
        sys.stderr.flush()

    return done


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
                # numba's index and data files, and the kernel's kept object
                # code (engine.native_code).
                if f.suffix in (".nbi", ".nbc", ".nbo", ".nbj") and \
                        f.name.split(".", 1)[0] in stems:
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
