"""How the compiled kernels are compiled: numba, its on-disk cache and its fallbacks, one parallel caller.

Caching. ``cache=True`` keeps machine code between processes. numba writes it next to the
source (``__pycache__``) and, where the package is installed read-only, in the user's cache
directory (``~/.cache/numba``, or ``NUMBA_CACHE_DIR``). Where neither is writable numba refuses
to decorate a cached function (``RuntimeError: no locator available``); ``jit`` then compiles
the same function without a cache, in memory: a read-only install still works and pays the
compile on first use in every process.

Freshness. numba keys each cached function on its own source file alone, but a kernel's machine
code holds the helpers it calls from the package's other modules and the constants it imports
(``metrics.linalg``'s limits...): after a change there, numba would load the old code. The
kernels' cache entries are keyed on every file that goes into them instead (``SOURCES``,
``sources_stamp``): a change to any of them compiles every kernel again.

One parallel caller. The ``prange`` kernels run on numba's ``workqueue`` threading layer (unless
``NUMBA_THREADING_LAYER`` says otherwise): its idle workers sleep, where OpenMP's spin, and on this
2-core machine shared with other work the 1000 x 1000 Inverse3 map took 0.45 s wall and 0.32 s CPU
on it against 1.0-1.2 s wall and 0.5 s CPU on ``omp``. ``workqueue`` must not be entered by two
threads at once: ``parallel_slot`` lets one caller at a time take the ``prange`` builds, and any
other thread runs the serial build of the same loop meanwhile (the same per-point results).

Loading without numba's registries. Before it loads a cached function numba refreshes its typing and
target contexts: it imports every implementation module it has (``numba.cpython.*``, ``numba.np.*``,
typed containers, jitclass...) and installs their registries. Machine code loaded from the cache
needs none of it: no typing, no lowering, only the symbols its object code links against. Without
it, numpy + ``import numba`` + the four cached functions of a 160 x 160 Inverse3 map took 0.45-0.57 s
of CPU against 0.53-0.75 s (six fresh processes each, interleaved, load average 8), and the whole
map 0.59 s of CPU against 0.91 s (medians of five, load 5). In numba 0.68 those symbols are
registered by the target context's creation (numba's C helpers, the math functions, the Python
API's objects), by the runtime's initialisation (``NRT_*``), by a parallel function's own reload
hook (the threading layer) and, of the implementation modules, by ``numba.cpython.hashing`` alone
(the hash secret): ``_QuickLoad`` provides those two and loads. An object code whose symbol were
missing would stop the process in LLVM, not raise, so this path is taken only for the numba
versions it was checked against (``QUICK_LOAD_NUMBA``); elsewhere, and for any function numba must
compile, numba's own refresh runs as before (numba's compiler refreshes the contexts itself,
``_numpy_support_without_blas_probe`` first). ``numba.np.arraymath`` is then imported only when
something compiles, or loads code of its own (``_blas_stood_in``).
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import os
import sys
import threading
import types
from pathlib import Path

import numba
from numba.core import caching

if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "workqueue"

#: The numba versions (major.minor) whose cache loading ``_QuickLoad`` was checked against: which
#: symbols a cached function's object code may need, and who registers them (module docstring).
QUICK_LOAD_NUMBA = ("0.68",)

_BLAS = "scipy.linalg.cython_blas"


class _DeferredModule(types.ModuleType):
    """Stands in for a module during one import; any use of it imports the real one and defers to it."""

    def __getattr__(self, name):
        real = sys.modules.get(self.__name__)
        if real is None or real is self:
            sys.modules.pop(self.__name__, None)
            real = importlib.import_module(self.__name__)
        return getattr(real, name)


@contextlib.contextmanager
def _blas_stood_in():
    """Within the block, ``scipy.linalg.cython_blas`` is a ``_DeferredModule`` (unless numba's numpy support or
    scipy's BLAS is imported already): ``numba.np.arraymath``, imported in it, skips its BLAS probe."""
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules or _BLAS in sys.modules:
        yield
        return
    stand_in = _DeferredModule(_BLAS)
    sys.modules[_BLAS] = stand_in
    try:
        yield
    finally:
        if sys.modules.get(_BLAS) is stand_in:
            del sys.modules[_BLAS]


def _numpy_support_without_blas_probe() -> None:
    """Import ``numba.np.arraymath`` (numba's refresh of its registries does, before a compile) without its BLAS probe.

    The probe imports ``scipy.linalg`` only to see whether it exists: 0.3 s of a short command's
    0.8 s of numba start-up on this machine (``isoforce stats DEV --json``, ``-X importtime``), for
    kernels that call no BLAS. While ``arraymath`` loads, ``scipy.linalg.cython_blas`` is a stand-in
    that imports the real module the moment anything reads from it; it is gone afterwards, so a
    later ``np.dot`` in a compiled function finds the real one. Where ``scipy.linalg`` is already
    imported there is nothing to save and nothing is stood in.
    """
    with _blas_stood_in():
        importlib.import_module("numba.np.arraymath")


class _QuickLoad(caching.FunctionCache):
    """numba's on-disk cache of one function, loading without refreshing numba's typing and target registries.

    A function found in the cache is rebuilt from its object code once the symbols it links against
    exist (the runtime's, the hash secret's; the module docstring says why these are all); one that is
    not found is compiled by numba, whose compiler refreshes the contexts itself.
    """

    def load_overload(self, sig, target_context):
        import numba.cpython.hashing  # noqa: F401  (registers the hash secret's symbols on import)
        from numba.core.runtime import nrt

        nrt.rtsys.initialize(target_context)
        # A cached function whose code holds one of numba's own (``np.sum``'s...) imports that one's module
        # as it loads (its environment): ``numba.np.arraymath`` then, whose BLAS probe the stand-in skips.
        with _blas_stood_in(), self._guard_against_spurious_io_errors():
            data = self._load_overload(sig, target_context)
        if data is None:                # numba compiles next: numpy support without the BLAS probe
            _numpy_support_without_blas_probe()
        return data


#: Whether cached functions load through ``_QuickLoad`` (this numba's version is one it was checked against).
QUICK_LOAD = (".".join(numba.__version__.split(".")[:2]) in QUICK_LOAD_NUMBA
              and all(hasattr(caching.Cache, name) for name in ("_load_overload", "_guard_against_spurious_io_errors")))
if not QUICK_LOAD:
    _numpy_support_without_blas_probe()     # numba's first cache load refreshes the registries

#: Whether the kernels were decorated with an on-disk cache (False: compiled in memory).
CACHED = True
_PACKAGE = Path(__file__).resolve().parent
#: What the kernels' machine code is made of: this package's modules and the modules whose
#: constants they compile in (``from metrics.linalg import FAST_COND_LIMIT`` ...).
SOURCES = (*sorted(_PACKAGE.glob("*.py")),
           *(_PACKAGE.parent / name for name in ("columns.py", "dynamics.py", "linalg.py", "statistics.py")))


@functools.cache
def sources_stamp() -> str:
    """SHA-256 of every file in ``SOURCES`` (names and bytes): the kernels' cache key.

    Returns
    -------
    str
    """
    digest = hashlib.sha256()
    for path in SOURCES:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


class _Stamped:
    """A numba cache locator for this package's functions whose freshness is ``sources_stamp``."""

    def get_source_stamp(self):
        return sources_stamp()

    @classmethod
    def from_function(cls, py_func, py_file):
        if not py_func.__module__.startswith(__package__ + "."):
            return None                 # another package's cached function: numba's own locators
        return super().from_function(py_func, py_file)


# Same places as numba's (NUMBA_CACHE_DIR, then __pycache__, then the user's cache), tried first
# (once a process: a second import of this module finds them there).
if not any(issubclass(c, _Stamped) for c in caching.CacheImpl._locator_classes):
    caching.CacheImpl._locator_classes[:0] = [
        type(f"Stamped{base.__name__}", (_Stamped, base), {})
        for base in (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator)]
_PARALLEL = threading.Lock()


def jit(parallel: bool = False, inline: bool = False, allocates: bool = False):
    """``numba.njit`` with ``cache=True``, ``nogil``, ``fastmath`` off; in memory where no cache dir is writable.

    Parameters
    ----------
    parallel : bool
        Compile ``prange`` loops for the cores.
    inline : bool
        Inline the function into its compiled callers (numba's IR, ``inline="always"``) instead of
        calling it: for the per-point function a loop calls with a dozen arrays (``_point``,
        ``blank``). Inlining every helper as well cost a 93 s cold compile for 3 % more speed.
    allocates : bool
        The function creates arrays, so it needs numba's reference counting (NRT). Without it
        (the default) an array handed to a compiled call is not reference-counted on each call:
        numba passes each array as a struct and, with NRT, counts its references at every call.

    Notes
    -----
    Measured on the 1000 x 1000 Inverse3 grid (one thread, ``FusedKernel``'s outputs allocated
    once): 234 ns a point before, 189 ns without NRT, 137 ns also with ``_point`` and ``blank``
    inlined; an unreachable point 114, 79 and 26 ns. The cold compile was 35 s in both cases.

    Returns
    -------
    callable
        A decorator.
    """
    options = {"nogil": True, "parallel": parallel, "error_model": "numpy", "inline": "always" if inline else "never",
               "_nrt": allocates}

    def wrap(func):
        try:
            dispatcher = numba.njit(cache=True, **options)(func)
        except RuntimeError:           # numba: "cannot cache function ...: no locator available"
            global CACHED
            CACHED = False
            _numpy_support_without_blas_probe()         # every first call compiles
            return numba.njit(cache=False, **options)(func)
        if QUICK_LOAD and type(dispatcher._cache) is caching.FunctionCache:
            dispatcher._cache.__class__ = _QuickLoad    # the same cache (no state of its own), loading quicker
        return dispatcher
    return wrap


def twins(func, name: str, allocates: bool = False):
    """``func`` compiled twice, ``(parallel, serial)``: its ``prange`` loops over the cores, and on the calling thread.

    One definition, two builds: numba runs ``prange`` as ``range`` where ``parallel`` is off. Each
    build is a copy of ``func`` named ``name + "_parallel"`` and ``name + "_serial"`` (name and
    qualname): numba's cache files are named after the qualname and the definition's line, so two
    builds of one function under one name would share, and overwrite, one cache entry.

    Parameters
    ----------
    func : function
        The loop, written with ``numba.prange``; no closure.
    name : str
        The builds' base name (the module attributes they are assigned to).
    allocates : bool
        The loop creates arrays (a scratch buffer per ``prange`` task): ``jit``'s ``allocates``.

    Returns
    -------
    tuple of Dispatcher
        ``(parallel build, serial build)``.
    """
    if func.__closure__:
        raise ValueError(f"{func.__qualname__} closes over variables: its cached builds could not tell them apart")
    builds = []
    for parallel, suffix in ((True, "parallel"), (False, "serial")):
        copy = types.FunctionType(func.__code__, func.__globals__, f"{name}_{suffix}", func.__defaults__)
        copy.__qualname__ = f"{name}_{suffix}"
        copy.__module__ = func.__module__
        copy.__doc__ = func.__doc__
        builds.append(jit(parallel=parallel, allocates=allocates)(copy))
    return builds[0], builds[1]


@contextlib.contextmanager
def parallel_slot(threads: bool):
    """Yield whether this caller may run the ``prange`` build (``threads`` and no other caller in it).

    Parameters
    ----------
    threads : bool
        The caller wants every core (``compute_map(threads=True)``).

    Yields
    ------
    bool
    """
    got = threads and _PARALLEL.acquire(blocking=False)
    try:
        yield got
    finally:
        if got:
            _PARALLEL.release()
