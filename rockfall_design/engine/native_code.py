"""The batch kernel's machine code, loaded without numba's compiler.

numba's cache holds the compiled kernel, but loading it through numba's
dispatcher first builds numba's whole target context: it imports numba's
typing and lowering registries (``numba.np.arraymath``, ``numba.np.linalg``
and through it ``scipy.linalg``, ``numpy.f2py``), about 0.5 s that every
command paid on its first run of the engine. The machine code itself needs
none of it.

So, once numba has compiled (or loaded) the kernel, its object code is kept
beside numba's cache (``<function>.native.nbo``, with ``.nbj`` describing it),
and a later process links it with LLVM's MCJIT (llvmlite, which numba brings)
and calls numba's own Python wrapper of it (the ``PyCFunction`` numba builds
for every compiled function, which unboxes the arguments and releases the GIL
for a ``nogil`` function) through ``ctypes``. The object refers to a few
symbols: the C API of Python, the C math library, and numba's C helpers and
memory runtime; those come from numba's C extension modules
(``_helperlib``, ``_dynfunc``, ``_nrt_python``), whose addresses numba
itself would register. Nothing of numba's compiler is loaded.

The wrapper trusts its arguments to have the types it was compiled for, so
each call checks them (dtype, dimensions, layout, writability of every
array) against the ones recorded; anything else, and every failure to load,
falls back to the dispatcher, which is always right. The kept code is valid
only for the engine sources, numba, llvmlite, Python and CPU it was made
with; all are recorded and checked.
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import json
import os
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

OBJECT_SUFFIX = ".nbo"
META_SUFFIX = ".nbj"
FORMAT = 1
"""Version of the files written here."""

_lock = threading.Lock()
_loaded: dict[str, NativeKernel | None] = {}
_exported: set[str] = set()
_engines: list[Any] = []  # MCJIT engines and environments kept alive for the process


def arg_tags(args: Sequence[Any]) -> list[Any]:
    """What numba's wrapper assumes of each argument: a nested list of type tags.

    Arrays by dtype, dimensions, C-contiguity, writability and alignment
    (numba types each as its own array type); named tuples by their fields;
    scalars by Python type.
    """
    import numpy as np

    def tag(a: Any) -> Any:
        if isinstance(a, np.ndarray):
            f = a.flags
            return ["a", a.dtype.str, a.ndim, bool(f.c_contiguous), bool(f.writeable),
                    bool(f.aligned)]
        if isinstance(a, tuple):
            return ["t", type(a).__name__, [tag(x) for x in a]]
        if isinstance(a, np.generic):
            return ["s", a.dtype.str]
        return ["p", type(a).__name__]

    return [tag(a) for a in args]


def _host() -> dict[str, str]:
    """What the machine code depends on besides the sources."""
    import llvmlite
    import llvmlite.binding as ll

    try:
        from importlib.metadata import version

        numba_version = version("numba")
    except Exception:  # noqa: BLE001 - then the recorded value cannot match
        numba_version = "?"
    return {
        "python": sys.version,
        "numba": numba_version,
        "llvmlite": llvmlite.__version__,
        "triple": ll.get_process_triple(),
        "cpu": ll.get_host_cpu_name(),
        "features": ll.get_host_cpu_features().flatten(),
    }


def _paths(cache_dir: Path, dispatcher: Any) -> tuple[Path, Path]:
    """Where the object code of ``dispatcher`` and its description are kept.

    Named as numba names its files (``<module>.<function>``), so that
    ``jit.drop_stale_cache`` removes them with numba's.
    """
    fn = dispatcher.py_func
    stem = f"{fn.__module__.rsplit('.', 1)[-1]}.{fn.__qualname__}.native"
    return cache_dir / (stem + OBJECT_SUFFIX), cache_dir / (stem + META_SUFFIX)


def export(dispatcher: Any, args: Sequence[Any], digest: str) -> bool:
    """Keep the object code of ``dispatcher``'s overload for ``args`` beside numba's cache.

    Called after the dispatcher has run with ``args`` (so the overload is
    compiled or loaded). Does nothing if a valid copy is there already, or
    once tried in this process. Never raises.

    Returns
    -------
    bool
        True if a copy was written.
    """
    key = f"{id(dispatcher)}"
    with _lock:
        if key in _exported:
            return False
        _exported.add(key)
    try:
        cache = dispatcher._cache
        if not getattr(cache, "_enabled", False):
            return False
        obj_path, meta_path = _paths(Path(cache._cache_path), dispatcher)
        tags = arg_tags(args)
        host = _host()
        if meta_path.is_file() and obj_path.is_file():
            with contextlib.suppress(Exception):
                old = json.loads(meta_path.read_text())
                if old.get("digest") == digest and old.get("tags") == tags and \
                        old.get("host") == host and old.get("format") == FORMAT:
                    return False
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        cres = dispatcher.overloads[sig]
        try:
            _, kind, data = cres.library.serialize_using_object_code()
        except RuntimeError:
            # Loaded from numba's cache: the object code is in its data file.
            cf = cache._cache_file
            entry = cf._load_index()[cache._index_key(sig, dispatcher.targetctx.codegen())]
            data_name = entry if isinstance(entry, str) else entry[-1]
            _, kind, data = cf._load_data(data_name)[0]
        if kind != "object":
            return False
        meta = {
            "format": FORMAT,
            "digest": digest,
            "tags": tags,
            "host": host,
            "wrapper": cres.fndesc.llvm_cpython_wrapper_name,
            "env": cres.fndesc.env_name,
        }
        # Written whole, then renamed: another process reads all or nothing.
        for path, content in ((obj_path, bytes(data[0])),
                              (meta_path, json.dumps(meta).encode())):
            tmp = path.with_name(f".{path.name}.{os.getpid()}")
            tmp.write_bytes(content)
            os.replace(tmp, path)
        return True
    except Exception:  # noqa: BLE001 - the dispatcher keeps working without it
        return False


class NativeKernel:
    """The kernel linked from its kept object code; call it like the dispatcher."""

    def __init__(self, fn: Callable[..., Any], tags: list[Any], keep: list[Any]) -> None:
        self._fn = fn
        self.tags = tags
        self._keep = keep

    def accepts(self, args: Sequence[Any]) -> bool:
        """True if ``args`` have exactly the types the code was compiled for."""
        return arg_tags(args) == self.tags

    def __call__(self, *args: Any) -> Any:
        return self._fn(None, args, None)


def _c_helpers(module: str) -> dict[str, int]:
    return dict(importlib.import_module(module).c_helpers)


def load(dispatcher: Any, digest: str) -> NativeKernel | None:
    """The kept machine code of ``dispatcher``, linked and ready, or None.

    Once per process and dispatcher (later calls return the same). None if
    nothing valid is kept (other sources, numba, llvmlite, Python or CPU) or
    linking fails; the caller then uses the dispatcher.
    """
    key = f"{id(dispatcher)}"
    with _lock:
        if key in _loaded:
            return _loaded[key]
        kernel = None
        try:
            kernel = _load(dispatcher, digest)
        except Exception:  # noqa: BLE001 - the dispatcher is the fallback
            kernel = None
        _loaded[key] = kernel
        return kernel


def _load(dispatcher: Any, digest: str) -> NativeKernel | None:
    if os.environ.get("ROCKFALL_DESIGN_NATIVE", "1") == "0":
        return None
    cache = dispatcher._cache
    if not getattr(cache, "_enabled", False):
        return None
    obj_path, meta_path = _paths(Path(cache._cache_path), dispatcher)
    if not (obj_path.is_file() and meta_path.is_file()):
        return None
    meta = json.loads(meta_path.read_text())
    if meta.get("format") != FORMAT or meta.get("digest") != digest:
        return None
    import llvmlite.binding as ll

    if meta.get("host") != _host():
        return None
    # The symbols numba registers with LLVM before it links anything
    # (numba.core.base._load_global_helpers, numba.core.runtime.nrt): its C
    # helpers, its memory runtime, None and the built-in exceptions.
    ll.add_symbol("_Py_NoneStruct", id(None))
    for module in ("numba._helperlib", "numba._dynfunc"):
        for py_name, address in _c_helpers(module).items():
            ll.add_symbol("numba_" + py_name, address)
    for py_name, address in _c_helpers("numba.core.runtime._nrt_python").items():
        ll.add_symbol(py_name if py_name.startswith("_") else "NRT_" + py_name, address)
    import builtins

    for obj in builtins.__dict__.values():
        if isinstance(obj, type) and issubclass(obj, BaseException):
            ll.add_symbol(f"PyExc_{obj.__name__}", id(obj))
    ll.initialize_native_target()
    ll.initialize_native_asmprinter()
    target = ll.Target.from_triple(ll.get_process_triple())
    tm = target.create_target_machine(cpu=ll.get_host_cpu_name(),
                                      features=ll.get_host_cpu_features().flatten(),
                                      codemodel="jitdefault", jit=True)
    empty = ll.parse_assembly("")
    empty.triple = ll.get_process_triple()
    engine = ll.create_mcjit_compiler(empty, tm)
    engine.add_object_file(ll.ObjectFileRef.from_data(obj_path.read_bytes()))
    engine.finalize_object()
    wrapper = engine.get_function_address(meta["wrapper"])
    env_slot = engine.get_global_value_address(meta["env"])
    if not wrapper or not env_slot:
        return None
    # The wrapper reads its Environment (numba's C struct: globals, consts)
    # from this global; a function that boxes no constants needs it only set.
    dynfunc = importlib.import_module("numba._dynfunc")
    env = dynfunc.Environment({})
    ctypes.c_void_p.from_address(env_slot).value = id(env)
    proto = ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.py_object, ctypes.py_object,
                              ctypes.py_object)
    fn = proto(wrapper)
    keep = [engine, tm, env, fn]
    _engines.append(keep)
    return NativeKernel(fn, meta["tags"], keep)
