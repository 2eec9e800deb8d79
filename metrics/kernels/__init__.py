"""Fused compiled kernels: inverse kinematics, J and the requested quantities in one pass over the points.

``metrics.quantities.evaluate`` (and so ``metrics.workspace.compute_map``) asks ``find`` for a
kernel before it walks the quantity graph in numpy. There is one when

- the mechanism's family has one (``FAMILIES``: registry kind -> its module),
- it computes every requested name (``FAMILIES``), and
- the loading has no torque bias (gravity off; either rating);

otherwise the numpy path runs as before. A request the kernel covers only in part runs in numpy
whole: split, the numpy graph redid the IK and J for its part, and ``isoforce stats fivebar_singh``
(then with apparent masses no kernel computed) took 2.2-2.3 s against 1.3-2.0 s. The mass
quantities (apparent-mass range, isotropic acceleration) need the family's kinetic form, compiled
beside its kernel (``<family>_mass.inertia``), and a mass model (``has_mass_model``); the isotropic
velocity needs the motors' speeds (``joint_speed_limits``). The tail shared by every family is
``dynamics``.

The numpy kernels stay the reference: the compiled pass hands every point it does not compute
to their formulas' accuracy (a hard or singular Jacobian, a scale far from 1, see ``square3``)
back to them, so those points get the numpy path's values and labels exactly.

``use_compiled(False)`` (or ``ISOFORCE_KERNELS=0`` in the environment) turns the kernels off,
for the tests that compare the two paths and for benchmarks. The first call in a process
compiles the kernels or loads them from numba's cache (``jit``); ``warm`` does that on purpose
and says how long it took.
"""
from __future__ import annotations

import contextlib
import importlib
import os
import sys
import threading
import time

import numpy as np

from kinematics.registry import MECHANISMS
from kinematics.registry import kind_of as _kind_of

#: The value columns of every kernel (``square3.COLUMNS``, ``dynamics.DYNAMIC_COLUMNS``, then the moments of a
#: platform, ``stewart``; repeated here so
#: that importing this package loads no numba: the kernels are compiled or loaded from the cache on first use).
COLUMNS = ("condition_number", "inverse_condition_number", "manipulability", "isotropic_force", "anisotropic_force",
           "spatial_resolution", "apparent_mass_min", "apparent_mass_max", "isotropic_acceleration",
           "isotropic_velocity", "isotropic_moment", "anisotropic_moment")
#: The mass quantities (``dynamics``): computed only for a model with a mass model (``has_mass_model``).
MASS_COLUMNS = COLUMNS[6:9]

__all__ = ["FAMILIES", "KERNEL_QUANTITIES", "FusedKernel", "compile_seconds", "enabled", "evaluate", "find",
           "registered_kind", "timing", "use_compiled", "warm"]

#: Families with a compiled kernel: registry kind -> its module (``pack``, ``run_parallel``, ``run_serial``)
#: and the quantities it computes (here, so that a request outside them loads no numba).
FAMILIES = {"inverse3": ("inverse3", COLUMNS + ("bottleneck",)),
            "fivebar": ("fivebar", COLUMNS + ("bottleneck", "singularity")),
            "serial_rrr": ("serial_rrr", COLUMNS + ("bottleneck", "singularity")),
            "delta": ("delta", COLUMNS + ("bottleneck", "singularity")),
            "stewart": ("stewart", ("condition_number", "inverse_condition_number", "isotropic_force",
                                    "anisotropic_force", "isotropic_moment", "anisotropic_moment",
                                    "apparent_mass_min", "apparent_mass_max", "isotropic_acceleration"))}
#: What the kernels compute, in some family (``FAMILIES``): the value columns and the classes.
KERNEL_QUANTITIES = frozenset(COLUMNS) | {"bottleneck", "singularity"}
_STATE = {"on": os.environ.get("ISOFORCE_KERNELS", "1") != "0", "seconds": 0.0}
_LOADED: set[tuple[str, bool]] = set()
_LOCAL = threading.local()          # use_compiled's choice, per thread


def enabled() -> bool:
    """Whether ``find`` hands out kernels (``use_compiled``; ``ISOFORCE_KERNELS=0`` turns them off).

    Returns
    -------
    bool
    """
    return getattr(_LOCAL, "on", _STATE["on"])


@contextlib.contextmanager
def use_compiled(on: bool):
    """Within the block, this thread uses the compiled kernels (``True``) or not (``False``, the numpy path).

    Parameters
    ----------
    on : bool

    Yields
    ------
    None
    """
    before = getattr(_LOCAL, "on", None)
    _LOCAL.on = bool(on)
    try:
        yield
    finally:
        if before is None:
            del _LOCAL.on
        else:
            _LOCAL.on = before


def registered_kind(mechanism) -> str | None:
    """The mechanism's registered kind (``kinematics.registry.kind_of``), ``None`` for an unregistered class.

    Compared by kind, not by class: a kernel names no model (``tests/test_mechanism_contract_only.py``),
    and the registry imports only the candidate's module.
    """
    try:
        return _kind_of(mechanism)
    except ValueError:            # a class that is not registered (a subclass): no kernel
        return None


class FusedKernel:
    """One family's compiled pass for one request: ``run(points)`` gives what ``evaluate`` returns."""

    def __init__(self, module, mechanism, names: tuple[str, ...], torque_limits: np.ndarray) -> None:
        from ..resolution import mechanism_steps

        self.module = module
        self.mechanism = mechanism
        self.names = tuple(names)
        self.params = module.pack(mechanism)
        self.torque_limits = np.ascontiguousarray(torque_limits, dtype=np.float64)
        steps = mechanism_steps(mechanism)
        self.steps = np.ones(mechanism.n_joints) if steps is None else np.ascontiguousarray(steps, dtype=np.float64)
        wanted = set(self.names)
        self.want_sv = bool(wanted & {"condition_number", "inverse_condition_number", "manipulability"})
        # A platform's moments come with its forces (``stewart``): the same J, the same generators.
        self.want_columns = bool(wanted & {"isotropic_force", "bottleneck", "spatial_resolution", "isotropic_moment"})
        self.want_vertices = bool(wanted & {"anisotropic_force", "anisotropic_moment"})
        self.want_mass = bool(wanted & {"apparent_mass_min", "apparent_mass_max"})
        self.want_acceleration = "isotropic_acceleration" in wanted
        # The family's kinetic form reads its bodies and rotors from here (``*_mass.pack_mass``).
        self.mass = (module.pack_mass(mechanism) if self.want_mass or self.want_acceleration else np.zeros(1))
        self.want_velocity = "isotropic_velocity" in wanted
        self.speeds = (np.ascontiguousarray(mechanism.joint_speed_limits(), dtype=np.float64) if self.want_velocity
                       else np.ones(mechanism.n_joints))

    def covers(self, grid) -> bool:
        """Whether the kernel computes ``grid``'s points itself (its module's ``covers``; True without one).

        Parameters
        ----------
        grid : GridSpec

        Returns
        -------
        bool
        """
        cover = getattr(self.module, "covers", None)
        return cover is None or bool(cover(grid))

    def run(self, points: np.ndarray, *, threads: bool = True, fill: bool = True):
        """The compiled pass over ``points`` (k, m): ``(feasible, joints, values, handed_back)``.

        Parameters
        ----------
        points : ndarray, shape (k, m)
            Task points, m.
        threads : bool
            Use every core (the ``prange`` build) when no other thread is in it.
        fill : bool
            ``nan`` in the value rows where not feasible. False (a family with ``SPARSE_VALUES``) leaves
            them unwritten, for a caller that reads the feasible points only: ten stores a point fewer, on
            most of a map's points (11-14 ms of the 1000 x 1000 Inverse3 pass's 0.23 s on one thread, 63 %
            of its points not feasible).

        Returns
        -------
        feasible : ndarray of bool, shape (k,)
        joints : ndarray, shape (k, n)
            ``nan`` where not feasible; any value anywhere without ``fill`` for a family with ``SPARSE_JOINTS``
            (a map reads no joint: the Inverse3 pass then decides most joints' limits without their angles).
        values : ndarray, shape (len(COLUMNS), k)
            One row per value column; ``nan`` where not feasible (with ``fill``) or not asked for; any
            value where not asked for, or not feasible without ``fill``.
        classes : dict of str to ndarray of int16, shape (k,)
            ``"bottleneck"`` and ``"singularity"``; ``-1`` where not feasible or not computed.
        handed_back : ndarray of bool, shape (k,)
            Points to recompute with the numpy path (whatever the other outputs say there).
        """
        x = np.ascontiguousarray(points, dtype=np.float64)
        k = x.shape[0]
        # Filled by the kernel, every point (``square3.blank`` first).
        feasible = np.empty(k, bool)
        joints = np.empty((k, self.mechanism.n_joints))
        values = np.empty((len(COLUMNS), k))
        classes = {"bottleneck": np.empty(k, np.int16), "singularity": np.empty(k, np.int16)}
        back = np.empty(k, bool)
        from .jit import parallel_slot

        sparse = (bool(fill),) if getattr(self.module, "SPARSE_VALUES", False) else ()
        with parallel_slot(threads and k > 1) as parallel:
            run = self.module.run_parallel if parallel else self.module.run_serial
            _load(self.module, parallel)
            run(x, self.params, self.torque_limits, self.steps, feasible, joints, values, classes["bottleneck"],
                classes["singularity"], back, self.want_sv, self.want_columns, self.want_vertices,
                self.mass, self.want_mass, self.want_acceleration, self.speeds, self.want_velocity, *sparse,
                *_scratch(self.module))
        return feasible, joints, values, classes, back


def _scratch(module) -> tuple:
    """The per-thread scratch a family's pass takes last (its module's ``block_scratch``), or nothing."""
    make = getattr(module, "block_scratch", None)
    return () if make is None else make()


def find(mechanism, names, loading) -> FusedKernel | None:
    """The compiled kernel for this request, or ``None`` (then the numpy path runs).

    Parameters
    ----------
    mechanism : Mechanism
        The model.
    names : tuple of str
        The requested quantities (already checked).
    loading : Loading
        The torque rating and gravity.

    Returns
    -------
    FusedKernel or None
    """
    if not enabled() or loading.biased:
        return None
    family = FAMILIES.get(registered_kind(mechanism))
    if family is None:
        return None
    if not names or not set(names) <= set(family[1]):
        return None
    if set(names) & set(MASS_COLUMNS) and not mechanism.has_mass_model:
        return None                  # the numpy path refuses them with the reason
    if "isotropic_velocity" in names and mechanism.joint_speed_limits() is None:
        return None                  # likewise: no motor speeds
    return FusedKernel(_module(family[0]), mechanism, tuple(names), loading.torque_limits(mechanism))


@contextlib.contextmanager
def timing():
    """Count the block's seconds into ``compile_seconds``: a kernel's first import, compile or cache load.

    Yields
    ------
    list of float
        One element, set to the block's seconds when it ends (what was added).
    """
    took = [0.0]
    start = time.perf_counter()
    try:
        yield took
    finally:
        took[0] = time.perf_counter() - start
        _STATE["seconds"] += took[0]


def _module(name: str):
    """The family's kernel module; its first import (numba's with it) is timed into ``compile_seconds``."""
    full = f"{__name__}.{name}"
    if full in sys.modules:
        return sys.modules[full]
    with timing():
        return importlib.import_module(full)


def _load(module, parallel: bool) -> None:
    """Compile ``module``'s build (or load it from numba's cache) on its first use, timed (``compile_seconds``)."""
    key = (module.__name__, parallel)
    if key in _LOADED:
        return
    kind = next(k for k, (name, _) in FAMILIES.items() if module.__name__.endswith("." + name))
    mech = MECHANISMS[kind]()
    x = np.zeros((2, mech.task_dim))
    run = module.run_parallel if parallel else module.run_serial
    sparse = (True,) if getattr(module, "SPARSE_VALUES", False) else ()
    with timing():
        run(x, module.pack(mech), np.ones(mech.n_joints), np.ones(mech.n_joints), np.zeros(2, bool),
            np.full((2, mech.n_joints), np.nan), np.full((len(COLUMNS), 2), np.nan), np.full(2, -1, np.int16),
            np.full(2, -1, np.int16), np.zeros(2, bool), True, True, True, np.zeros(1), True, True,
            np.ones(mech.n_joints), True, *sparse, *_scratch(module))
    _LOADED.add(key)


def warm(threads: bool = True) -> float:
    """Compile (or load from numba's cache) every family's kernels now; seconds it took (0 when loaded).

    Parameters
    ----------
    threads : bool
        Also the ``prange`` builds.

    Returns
    -------
    float
    """
    before = _STATE["seconds"]
    for name, _ in FAMILIES.values():
        module = _module(name)
        for parallel in (False, True) if threads else (False,):
            _load(module, parallel)
    partials = _module("partials")
    _load_partials(partials, False)
    _STATE["seconds"] += partials.load_grid_quantiles()
    _load_twin_batch(threads)
    _load_wrench()
    _load_points()
    return _STATE["seconds"] - before


def _load_points() -> None:
    """The grid points' fill (``points``), every map's first step, timed: a 2 x 2 grid's first point."""
    from kinematics.grid import GridSpec

    grid_points(GridSpec(axes=("x", "y"), lower=(0.0, 0.0), upper=(1.0, 1.0), resolution=(2, 2)), ("x", "y"), (0, 1))


def _load_wrench() -> None:
    """The gravity-biased wrench slices' vertex enumeration (``wrench``): a square's slabs, timed."""
    module = _module("wrench")
    if module.__name__ in _LOADED:
        return
    a = np.zeros((3, 2, 1))
    a[0, 0, 0] = a[1, 1, 0] = a[2, 0, 0] = a[2, 1, 0] = 1.0          # x, y and x + y: three slabs in the plane
    faces = np.array([[False, False], [False, True], [True, False], [True, True]])
    with timing():
        module.slab_vertices(a, -np.ones((3, 1)), np.ones((3, 1)), np.array([[0, 1], [0, 2], [1, 2]], np.intp),
                             faces, np.full(1, -1.0), np.zeros((0, 2)))
    _LOADED.add(module.__name__)


def _load_twin_batch(threads: bool) -> None:
    """The design studies' Twin-Pantograph kernel (``twin_batch``): one pair, timed into ``compile_seconds``."""
    module = _module("twin_batch")
    params = MECHANISMS["twin_pantograph"]().params
    for parallel in (False, True) if threads else (False,):
        key = (module.__name__, parallel)
        if key in _LOADED:
            continue
        run = module.run_parallel if parallel else module.run_serial
        with timing():
            run(np.zeros((1, 5)), np.ones((1, 4)), np.array([0, 1], np.int64), np.ones((1, 6)), np.ones(6, bool),
                np.ones(5), module.pack(params), True, module.lane_buffer(1), np.empty((1, 1)), np.empty((1, 1)))
        _LOADED.add(key)


def compile_seconds() -> float:
    """Seconds this process spent compiling kernels or loading them from the cache (numba's import included).

    Returns
    -------
    float
    """
    return _STATE["seconds"]


def evaluate(kernel: FusedKernel, points: np.ndarray, names, fallback, *, threads: bool = True, fill: bool = True):
    """The requested quantities at ``points`` (..., m) by ``kernel``; handed-back points by ``fallback``.

    Parameters
    ----------
    kernel : FusedKernel
        From ``find``.
    points : ndarray, shape (..., m)
        Task points, m (checked by the caller).
    names : tuple of str
        The requested quantities.
    fallback : callable ``(points (k, m)) -> Evaluation``
        The numpy path (``metrics.quantities``), for the points the closed forms hand back
        (singular or ill-conditioned poses, extreme scales): their values and labels are its own.
    threads : bool
        Use every core when no other thread is in the compiled pool.
    fill : bool
        False: the values where not feasible are unspecified (``FusedKernel.run``), for a caller that
        reads the feasible points only.

    Returns
    -------
    feasible : ndarray of bool, shape (...)
    joints : ndarray, shape (..., n_joints)
    values : dict of str to ndarray, shape (..., ...)
    """
    mech = kernel.mechanism
    batch = points.shape[:-1]
    flat = points.reshape(-1, mech.task_dim)
    feasible, joints, table, classes, back = kernel.run(flat, threads=threads, fill=fill)
    values = {}
    for name in kernel.names:
        if name in ("bottleneck", "singularity"):
            values[name] = classes[name]
        else:
            values[name] = table[COLUMNS.index(name)]
    if back.any():
        at = np.flatnonzero(back)
        with use_compiled(False):
            ref = fallback(flat[at])
        feasible[at], joints[at] = ref.feasible, ref.joints
        for name in names:
            values[name][at] = ref.values[name]
    return (feasible.reshape(batch), joints.reshape(batch + (mech.n_joints,)),
            {name: values[name].reshape(batch + values[name].shape[1:]) for name in names})


def chunk_partials(values: list[np.ndarray], regular: np.ndarray, singular: np.ndarray, bounded: np.ndarray,
                   index: np.ndarray, shape: tuple[int, ...], subgrids: tuple[bool, ...], ends: list[bool], *,
                   histogram: bool, threads: bool = True) -> list[list]:
    """``statistics.chunk_partial`` of every quantity on the full grid and its sub-grids, compiled (``partials``).

    Parameters
    ----------
    values : list of ndarray, shape (k,)
        Each quantity at the chunk's feasible points.
    regular, singular, bounded : ndarray of bool, shape (k,)
        As ``chunk_partial`` takes them (``bounded`` enters only where ``ends`` says).
    index : ndarray of int, shape (k,)
        The points' flat grid indices.
    shape : tuple of int
        The grid's resolution.
    subgrids : tuple of bool
        Which sub-grids after the full one exist, in ``partials.GRIDS`` order: the two half grids, then
        the two quarter grids (``map_chunks.sub_grid``); fewer entries leave the rest out.
    ends : list of bool
        Per quantity, whether ``bounded`` singular points enter its extremes.
    histogram : bool
        Also bin the values (streamed maps).
    threads : bool
        Use every core when no other thread is in the compiled pool.

    Returns
    -------
    list of list
        Per quantity, ``[full, *subgrids]`` ``statistics.Partial`` (``None`` for a missing sub-grid).
    """
    from ..statistics import Partial, _histogram
    from . import partials as comp
    from .jit import parallel_slot

    k = len(index)
    grids = np.array([True, *subgrids])
    ng = len(grids)
    index = np.ascontiguousarray(index, np.int64)
    shape = np.array(shape, np.int64)
    members, mask, edge = comp.scratch(k)
    sizes, n_singular = np.empty(ng, np.int64), np.empty(ng, np.int64)
    singular_at = np.empty((ng, comp.SINGULAR_LOCATIONS), np.int64)
    _load_partials(comp, False)
    n_edge = comp.prepare(index, shape, grids, regular, singular, bounded, members, mask, edge, sizes, n_singular,
                          singular_at)
    room = int(np.minimum(sizes, comp.DENSE_BINS).sum())
    # Shared by every quantity's Partial, so read-only.
    located = []
    for g, ns in enumerate(n_singular.tolist()):
        located.append(singular_at[g, :min(ns, comp.SINGULAR_LOCATIONS)].copy())
        located[-1].flags.writeable = False
    n_singular = n_singular.tolist()

    def one(q: int) -> list:
        row = np.ascontiguousarray(values[q], np.float64)
        whole, real = np.empty((3, ng), np.int64), np.empty((5, ng))
        bins, dense = np.empty((ng, 2), np.int64), np.empty(ng, bool)
        keys, counts, lows, highs = comp.bins_out(room)     # this thread's
        comp.quantity(row, index, shape, grids, members, sizes, mask, edge, n_edge, bool(ends[q]), bool(histogram),
                      whole, real, bins, dense, comp.table(), keys, counts, lows, highs)
        (count, argmin, argmax), (mean, m2, scale, lo, hi) = whole.tolist(), real.tolist()
        spans, flat = bins.tolist(), dense.tolist()
        parts = []
        for g in range(ng):
            if not grids[g]:
                parts.append(None)
                continue
            hist = (None, None, None, None)
            if histogram and count[g]:
                if flat[g]:     # copies: the scratch is the next quantity's
                    a, b = spans[g]
                    hist = (keys[a:b].copy(), counts[a:b].copy(), lows[a:b].copy(), highs[a:b].copy())
                else:           # more than DENSE_BINS keys: sorted instead
                    v = row[members[g, :sizes[g]]]
                    hist = _histogram(np.sort(v[np.isfinite(v)]))
            parts.append(Partial(count[g], mean[g], m2[g], scale[g], lo[g], hi[g], argmin[g], argmax[g],
                                 n_singular[g], located[g], *hist))
        return parts

    # One quantity at a time, its values as they come (not copied into one table), on this thread and,
    # with ``threads``, on a helper thread too (``partials.shared``: never waiting for it to start).
    with parallel_slot(threads and comp.shares(len(values), k)) as parallel:
        return comp.shared(len(values), one, helper=parallel)


def _load_partials(comp, parallel: bool) -> None:
    """``_load`` for the statistics' build: one tiny chunk, timed into ``compile_seconds``."""
    key = (comp.__name__, parallel)
    if key in _LOADED:
        return
    with timing():
        index, shape, grids = np.zeros(1, np.int64), np.array([2, 2], np.int64), np.ones(5, bool)
        members, mask, edge = comp.scratch(1)
        sizes = np.zeros(5, np.int64)
        for take in (False, True):       # no regular point, then one: every branch's types
            flags = np.array([take])
            n_edge = comp.prepare(index, shape, grids, flags, ~flags, ~flags, members, mask, edge, sizes,
                                  np.zeros(5, np.int64), np.zeros((5, comp.SINGULAR_LOCATIONS), np.int64))
            comp.quantity(np.ones(1), index, shape, grids, members, sizes, mask, edge, n_edge, take, take,
                          np.zeros((3, 5), np.int64), np.zeros((5, 5)), np.zeros((5, 2), np.int64), np.zeros(5, bool),
                          comp.table(), *comp.bins_out(5))
    _LOADED.add(key)


def exact_grid_quantiles(values: np.ndarray, regular: np.ndarray, grids, lo: float, hi: float) -> list:
    """``partials.exact_grid_quantiles``, its first load timed into ``compile_seconds``.

    Parameters
    ----------
    values : ndarray, shape ``resolution``
    regular : ndarray of bool, shape ``resolution``
    grids : sequence of bool
    lo, hi : float

    Returns
    -------
    list of dict or None
    """
    comp = _module("partials")
    _STATE["seconds"] += comp.load_grid_quantiles()
    return comp.exact_grid_quantiles(values, regular, grids, lo, hi)


def grid_points(grid, task_names, span: tuple[int, int], *, threads: bool = True) -> np.ndarray:
    """``grid.points(task_names, slice(*span))``, compiled (``points``): the same numbers, bit for bit.

    Parameters
    ----------
    grid : GridSpec
        The grid.
    task_names : tuple of str
        The mechanism's task coordinates, in order.
    span : tuple of int
        ``[start, stop)`` flat grid indices.
    threads : bool
        Accepted for the callers' symmetry; the fill is one memory-bound pass on this thread.

    Returns
    -------
    ndarray, shape (stop - start, m)
    """
    del threads
    from . import points as comp

    start, stop = span
    out = np.empty((stop - start, len(task_names)))
    args = comp.layout(grid, task_names)
    key = (comp.__name__, False)
    if key not in _LOADED:
        with timing():
            comp.fill(0, np.empty((1, len(task_names))), *args)
        _LOADED.add(key)
    comp.fill(start, out, *args)
    return out
