"""Design-vectorised Twin-Pantograph: the force GII's per-sample singular values for many designs at once.

``metrics.design.evaluators.Generic`` builds one ``TwinPantograph`` per design and runs its IK,
``force_map`` and a LAPACK SVD: about 2.5 ms of Python per design on a probe of 8 samples, and
10 us per (design, sample) pair on a whole workspace (profiled on ``twin_pantograph_distance``).
The culling search asks mostly for the first shape (every design on a few probes), so at paper
001's Table VII size (22 million designs) the per-design overhead alone is 15 hours.

Here the work is compiled (``metrics.kernels.twin_batch``, numba): one pass over (geometry,
sample) items, a geometry being ``(l1, l2, l3, l6)`` and its designs a run of consecutive designs
that share it (Table VII's ids vary ``Q1`` fastest, so its 26 torques are one run):

========================================  ===========================================================
what                                      computed once per
========================================  ===========================================================
pen frame ``R = (a, p, b)``, U-joint      (geometry, sample), in scalars: no temporaries
centres, waist angles ``psi``, plane
frames ``e_r, n``, U-joint bends, the
five-bar IK and the six force-map rows
torque scaling, Gram matrix, its extreme  (design, sample); the Gram matrices of 8 pairs are
eigenvalues (cyclic Jacobi, no LAPACK)    diagonalised side by side (AVX2 lanes)
========================================  ===========================================================

On ``twin_pantograph_distance`` at 25 cm this costs 0.69-0.75 us CPU per pair on a whole
workspace (the Jacobi 0.32 us of it, the IK's 20 libm calls most of the rest) against the numpy
pass's 3.47-4.53 us in the same runs (``scripts/bench_optimize.py``, 3 runs, load average 4-6).
The numpy pass (``_numpy_values``: each sub-expression at the level of the parameters it depends
on, the pen frame per sample, the waist and bends per ``(l6, sample)``, the IK and rows per
geometry and sample, ``numpy.linalg.eigvalsh`` per pair) stays as the reference the tests
compare with, and runs where the compiled kernels are off (``metrics.kernels.use_compiled(False)``,
``ISOFORCE_KERNELS=0``). The kernel's first use compiles it (18 s cold on this machine, loaded)
or loads it from numba's cache (0.36 s).

The force map's rows take a closed form. With a joint's Cartesian gradient ``g`` (a unit's
tip velocity per joint rate, as in ``TwinPantograph._twist_rows``), its twist row is ``[g, m]``
with ``m = -s h g x p`` (``s = -1`` for unit A, ``+1`` for B), and the 5-DOF task basis
takes ``(m . a, m . b)``. With ``a x p = b`` (a right-handed pen frame), ``m . a = s h
g . b`` and ``m . b = -s h g . a``, so no cross product is formed: the row of the force
map in the pen frame (paper 001: "the Jacobian is expressed in the end-effector coordinate
frame prior to scaling") is ``(g.a, g.p, g.b, s h g.b, -s h g.a)``, ``h = ujoint_lever * l6``
(each U-joint's distance from the task point, ``l6 / 2`` by default); in the
base frame its first three entries are ``g`` itself.

The scaled matrix is ``M = S_T^-1 A S_J`` (``metrics.gii.scaled_matrix``, ``kind =
"force_map"``; both scalings as ratios to their first entry, eqs. 12-13), 5 x 6 with the
redundant waist. Its extreme singular values are the square roots of the extreme eigenvalues
of the 5 x 5 Gram matrix ``M M^T``.

Accuracy against ``Generic`` (``tests/metrics/test_twin_batch.py``): the geometry is the
model's formulas in the same order, except the closed-form rows above and ``R^T`` applied
row by row, which differ by a few ulps of the rows' size (libm's transcendental functions in
the kernel against numpy's, an ulp apart at most). The eigenvalues of a Gram matrix formed in
floating point carry an absolute error of order ``eps sigma_max^2`` (forming ``M M^T`` with
6-term sums, then a backward-stable symmetric eigensolver: the kernel's Jacobi, whose bound
``(GAMMA R + 1) eps tr(G)`` its module doc derives), so ``sigma_min`` carries ``eps sigma_max^2 /
sigma_min``: relative error ``eps kappa^2`` with ``kappa = sigma_max / sigma_min`` at that
sample, against ``eps kappa`` for the SVD. The near-optimal designs have ``kappa <= 1 / GII`` (a
few) at every sample; only nearly singular samples, whose GII is near 0 either way, lose digits.

What the culling search needs (``metrics.design.culling``) holds: a pair's value depends on
the pair only, never on which other pairs share the call, nor on the thread count: each item
is the same scalar code whatever the call, and a Jacobi lane whose off-diagonal entry is
negligible gets the identity rotation (``c = 1``, ``s = 0``), which changes none of its bits,
so its neighbours in the lanes change nothing (``tests/metrics/test_twin_batch_kernel.py``).

================================  ==========================================================
function / class                  returns
================================  ==========================================================
``supports(study)``               whether a study's grid and objective fit this evaluator
``TwinBatch``                     the study evaluator (``metrics.design.evaluators.Evaluator``)
``force_gii_values``              ``(sigma_min, sigma_max)`` (k, m) of designs x samples
================================  ==========================================================
"""
from __future__ import annotations

import numpy as np

from kinematics import kind_of
from kinematics.arrays import BoolArray, FloatArray
from kinematics.rotations import tilt_matrix

from .. import kernels
from .evaluator import Evaluator

#: Design fields the batch evaluates; any other varied field needs ``Generic``.
FIELDS = frozenset({"shoulder_separation", "upper_arm", "forearm", "pen_length", "motor_torques", "gear_ratios"})
#: (design, sample) pairs per internal block: about 1 kB of temporaries each, so ~64 MB.
BLOCK_PAIRS = 1 << 16
#: (geometry, sample) items from which a call takes every core (below, starting the threads costs more).
PARALLEL_ITEMS = 4096
#: Chunks of a parallel call (a few per core, for a core that another process slows).
PARALLEL_CHUNKS = 8
_SLACK = 8 * np.finfo(float).eps     # as TwinPantograph: cosines a few ulps beyond 1 are clipped
_TWO_PI = 2.0 * np.pi


def supports(study) -> bool:
    """Whether ``study`` is a force-GII study of a 5-DOF Twin-Pantograph over ``FIELDS``.

    Parameters
    ----------
    study : metrics.design.Study
        A built study.

    Returns
    -------
    bool
        ``True`` for a ``TwinPantograph`` with the roll passive (task ``x, y, z, rx, rz``), a
        ``gii`` objective and only ``FIELDS`` on the grid.
    """
    mech = study.mechanism
    fields = {t.field for p in study.parameters for t in p.targets}
    return (kind_of(mech) == "twin_pantograph" and not mech.six_dof and study.objective.kind == "gii"
            and study.workspace.sampling is None and fields <= FIELDS and midpoint_reading(mech))


def midpoint_reading(mech) -> bool:
    """Whether ``mech``'s task point is the midpoint of its U-joints (``reference_along`` and
    ``reference_offset`` zero), any ``ujoint_lever``: the readings the closed-form rows below
    implement (``h = ujoint_lever * l6``); the others go to ``Generic``.

    Parameters
    ----------
    mech : TwinPantograph

    Returns
    -------
    bool
    """
    p = mech.params
    return p.reference_along == 0.0 and p.reference_offset == 0.0


class TwinBatch(Evaluator):
    """Twin-Pantograph force-GII designs vectorised with ``force_gii_values`` (see the module doc)."""

    def __init__(self, study) -> None:
        super().__init__(study)
        self.points = study.workspace.points
        self.note = "design-vectorised Twin-Pantograph force GII (metrics.design.twin_batch)"

    def values(self, fields, sample_pos):
        """Per-sample ``(sigma_min, sigma_max)`` of k designs, all in one vectorised pass.

        Parameters
        ----------
        fields : dict of str to ndarray
            SI values of the varied fields, one row per design: shape (k,) for a scalar field,
            (k, 7) for a per-joint one (``Study.field_values``).
        sample_pos : ndarray of int, shape (m,)
            Positions into ``study.workspace.points``.

        Returns
        -------
        (ndarray, ndarray), each of shape (k, m)
            ``nan`` where infeasible.
        """
        obj = self.study.objective
        return force_gii_values(self.study.mechanism, fields, self.points[sample_pos], s_t=obj.s_t, frame=obj.frame)


def _angle_in(angle: FloatArray, lower: float, upper: float) -> BoolArray:
    """``kinematics.angles.wrap_into`` followed by the model's limit check (``feasible``)."""
    shifted = angle - _TWO_PI * np.floor((angle - lower) / _TWO_PI)
    return (shifted >= lower) & (shifted <= upper)


class _Poses:
    """Sample-level quantities: centre (m, 3) and pen frame columns ``a, p, b`` (m, 3)."""

    def __init__(self, points: FloatArray) -> None:
        rot = tilt_matrix(points[:, 3:5])
        self.centre = points[:, :3]
        self.a, self.p, self.b = rot[:, :, 0], rot[:, :, 1], rot[:, :, 2]


def _unit_pen(poses: _Poses, idx: np.ndarray, h: FloatArray, y0: float, sign: float, params) -> dict:
    """(l6, sample) level for one unit: tip, waist, plane frame, bend and waist limit.

    ``idx`` (P,) picks samples of ``poses``, ``h`` (P,) each pair's U-joint distance from the task point;
    ``sign`` is ``-1`` for unit A (the tip at ``centre - h p``), ``+1`` for unit B.
    """
    p = poses.p[idx]
    tip = poses.centre[idx] + (sign * h)[:, None] * p
    dy, dz = tip[:, 1] - y0, tip[:, 2]
    psi = np.arctan2(-dy, dz)
    w = np.hypot(dy, dz)
    s, c = np.sin(psi), np.cos(psi)
    # er = (0, -s, c), n = e_x x e_r = (0, -c, -s) (TwinPantograph._plane_frame)
    pn_y, pn_z = p[:, 1] * c, p[:, 2] * s
    # bend = angle(p, -n) (rotations.angle_between): |p x -n| and p . -n
    cx = np.stack([p[:, 1] * s - p[:, 2] * c, -(p[:, 0] * s), p[:, 0] * c], -1)
    bend = np.arctan2(np.sqrt(np.sum(cx * cx, -1)), pn_y + pn_z)
    joint = 0 if sign < 0 else 3
    ok = (bend <= params.ujoint_limit) & _angle_in(psi, params.lower_limits[joint], params.upper_limits[joint])
    a, b = poses.a[idx], poses.b[idx]
    return {"u": tip[:, 0], "w": w, "ok": ok,
            # projections of e_x, e_r and n on the pen frame (a, p, b): the rows' pen components
            "ex": (a[:, 0], p[:, 0], b[:, 0]),
            "er": (-s * a[:, 1] + c * a[:, 2], -s * p[:, 1] + c * p[:, 2], -s * b[:, 1] + c * b[:, 2]),
            "n": (-c * a[:, 1] - s * a[:, 2], -c * p[:, 1] - s * p[:, 2], -c * b[:, 1] - s * b[:, 2]),
            "er_base": (s, c)}


def _unit_rows(unit: dict, l1, l2, l3, h, sign: float, params, first: int, frame: str):
    """(geometry, sample) level for one unit: the waist and two shoulder rows, (P, 3, 5), and ``ok``."""
    u, w = unit["u"], unit["w"]
    ok = unit["ok"].copy()
    rows = []
    # waist row: g = n / w (TwinPantograph._twist_rows: r_psi)
    gs = [(0.0, 1.0 / w)]                               # (coefficient of e_x, coefficient of n)
    for j, (sx, branch) in enumerate(((-0.5 * l1, 1.0), (0.5 * l1, -1.0))):
        d0, d1 = u - sx, w
        rho = np.hypot(d0, d1)
        cos_e = (l2 * l2 + rho * rho - l3 * l3) / (2.0 * l2 * rho)
        ok &= np.abs(cos_e) <= 1.0 + _SLACK
        theta = np.arctan2(d1, d0) + branch * np.arccos(np.clip(cos_e, -1.0, 1.0))
        ok &= _angle_in(theta, params.lower_limits[first + 1 + j], params.upper_limits[first + 1 + j])
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        dist0 = u - (sx + l2 * cos_t)
        dist1 = w - (0.0 + l2 * sin_t)
        denom = l2 * (dist0 * -sin_t + dist1 * cos_t)
        gs.append((dist0 / denom, dist1 / denom))       # g = (dist0 e_x + dist1 e_r) / denom
    ex, er, n = unit["ex"], unit["er"], unit["n"]
    if frame == "base":
        s, c = unit["er_base"]
    for j, (alpha, beta) in enumerate(gs):
        basis = n if j == 0 else er                     # the waist row lies along n, the others in the plane
        ga = alpha * ex[0] + beta * basis[0]
        gb = alpha * ex[2] + beta * basis[2]
        if frame == "end_effector":
            gp = alpha * ex[1] + beta * basis[1]
            force = (ga, gp, gb)
        elif j == 0:                                    # base frame: g itself; n = (0, -c, -s)
            force = (np.zeros_like(ga), -c * beta, -s * beta)
        else:                                           # e_r = (0, -s, c)
            force = (np.broadcast_to(alpha, ga.shape), -s * beta, c * beta)
        rows.append(np.stack([force[0], force[1], force[2], sign * h * gb, -sign * h * ga], -1))
    return np.stack(rows, -2), ok


def force_gii_values(mech, fields: dict[str, np.ndarray], points: FloatArray, *,
                     s_t, frame: str = "end_effector", threads: bool = True) -> tuple[FloatArray, FloatArray]:
    """``sigma_min`` and ``sigma_max`` of the scaled force map for designs x samples.

    The per-sample values of paper 001's force GII (eq. 11) as ``Generic`` computes them
    (``metrics.gii.scaled_singular_values`` of ``TwinPantograph.force_map``, ``kind =
    "force_map"``, ``s_j`` the joint-side torque limits); ``nan`` where a design cannot reach a
    sample or breaks a limit (``TwinPantograph.feasible``), ``inf`` where the force map has a
    non-finite entry (an exact singularity), as ``metrics.linalg.singular_values``.

    Parameters
    ----------
    mech : TwinPantograph
        The base model (5-DOF task); fields not in ``fields`` are its own.
    fields : dict of str to ndarray
        SI values of the varied ``FIELDS``, one row per design: (k,) for the lengths, (k, 7)
        for ``motor_torques`` / ``gear_ratios`` (``Study.field_values``).
    points : ndarray, shape (m, 5)
        Poses ``(x, y, z, rx, rz)``, m and rad.
    s_t : sequence of float, length 5
        Task scaling ``S_T`` (SI: forces 1, moments in m).
    frame : {"end_effector", "base"}
        The frame of the force rows before scaling.
    threads : bool
        Use every core (the kernel's ``prange`` build) when no other thread of this process is
        in it, worker processes too: a study's warm-up chunk and its last chunks run alone. Two
        worker processes of two threads each on this 2-core machine were not slower than two
        serial ones on whole-workspace evaluations (1.03 against 1.62 us wall per pair, at a
        load average of 5 from other work, where more threads also take a larger share of the
        machine). The values are the same bits either way.

    Returns
    -------
    sigma_min, sigma_max : ndarray, shape (k, m)
        Dimensionless (N per N m times N m per N).

    Examples
    --------
    >>> from kinematics import mechanism_class
    >>> mech = mechanism_class("twin_pantograph")()
    >>> a, b = force_gii_values(mech, {"pen_length": np.array([0.07, 0.09])}, mech.home_pose()[None],
    ...                         s_t=(1.0, 1.0, 1.5, 0.036, 0.039))
    >>> a.shape, bool(np.all(a <= b))
    ((2, 1), True)
    """
    if mech.six_dof:
        raise ValueError("force_gii_values needs the 5-DOF Twin-Pantograph (roll_actuator = 'passive')")
    if not midpoint_reading(mech):
        raise ValueError("force_gii_values models a task point at the U-joints' midpoint only (reference_along "
                         "and reference_offset 0); use metrics.design.evaluators.Generic for the others")
    if frame not in ("end_effector", "base"):
        raise ValueError(f"frame must be 'end_effector' or 'base', got {frame!r}")
    bad = set(fields) - FIELDS
    if bad:
        raise ValueError(f"fields must be among {', '.join(sorted(FIELDS))}, got {sorted(bad)}")
    x = np.asarray(points, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 5:
        raise ValueError(f"points must have shape (m, 5), got {x.shape}")
    st = np.asarray(s_t, dtype=np.float64)
    if st.shape != (5,) or not np.all(np.isfinite(st) & (st > 0.0)):
        raise ValueError(f"s_t must be 5 positive finite numbers, got {st.tolist()}")
    st = st / st[0]                              # eq. 13 as metrics.gii: ratios to the first task force
    params = mech.params
    k = next(iter(fields.values())).shape[0] if fields else 1
    geo_names = ("shoulder_separation", "upper_arm", "forearm", "pen_length")
    geo = np.stack([np.broadcast_to(np.asarray(fields.get(n, getattr(params, n)), float), (k,))
                    for n in geo_names], -1)
    motor = np.broadcast_to(np.asarray(fields.get("motor_torques", params.motor_torques), float), (k, 7))
    gear = np.broadcast_to(np.asarray(fields.get("gear_ratios", params.gear_ratios), float), (k, 7))
    act = list(mech.actuated)
    scale = (motor * gear)[:, act]                                   # (k, n) joint-side torque limits
    scale = scale / scale[:, :1]                 # eq. 12 as metrics.gii: ratios to the first actuator's
    if kernels.enabled():
        return _compiled(x, geo, scale, act, st, frame, params, threads)
    return _numpy_values(x, geo, scale, act, st, frame, params)


def _compiled(x, geo, scale, act, st, frame, params, threads: bool) -> tuple[FloatArray, FloatArray]:
    """``force_gii_values`` by ``metrics.kernels.twin_batch``: runs of designs sharing a geometry."""
    from metrics.kernels import twin_batch as comp
    from metrics.kernels.jit import parallel_slot

    k, m = geo.shape[0], x.shape[0]
    # A run: consecutive designs with one (l1, l2, l3, l6) (Table VII's ids vary Q1 fastest), whose
    # rows the kernel computes once per sample. O(k), where np.unique(axis=0) sorted.
    new = np.ones(k, bool)
    new[1:] = np.any(geo[1:] != geo[:-1], axis=1)
    first = np.flatnonzero(new)
    starts = np.append(first, k).astype(np.int64)
    geo_runs = np.ascontiguousarray(geo[first])
    scale6 = np.zeros((k, 6))
    scale6[:, act] = scale
    keep = np.zeros(6, bool)
    keep[act] = True
    a_out = np.empty((k, m))
    b_out = np.empty((k, m))
    with parallel_slot(threads and len(first) * m >= PARALLEL_ITEMS) as parallel:
        run = comp.run_parallel if parallel else comp.run_serial
        lanes = comp.lane_buffer(PARALLEL_CHUNKS if parallel else 1)
        run(np.ascontiguousarray(x), geo_runs, starts, scale6, keep, np.ascontiguousarray(st), comp.pack(params),
            frame == "end_effector", lanes, a_out, b_out)
    # A pair whose Jacobi met the sweeps' cap has no bounded result (the kernel's doc): LAPACK's.
    for d in np.flatnonzero(np.any(a_out == comp.HANDED_BACK, axis=1)):
        js = np.flatnonzero(a_out[d] == comp.HANDED_BACK)
        a_d, b_d = _numpy_values(x[js], geo[d:d + 1], scale[d:d + 1], act, st, frame, params)
        a_out[d, js], b_out[d, js] = a_d[0], b_d[0]
    return a_out, b_out


def _numpy_values(x, geo, scale, act, st, frame, params) -> tuple[FloatArray, FloatArray]:
    """``force_gii_values`` in numpy: the reference of the compiled pass (``kernels.use_compiled(False)``)."""
    k = geo.shape[0]
    uniq, geo_of = np.unique(geo, axis=0, return_inverse=True)       # share the force map across torques
    geo_of = geo_of.reshape(-1)
    poses = _Poses(x)
    m = x.shape[0]
    a_out = np.empty((k, m))
    b_out = np.empty((k, m))
    keep = act                       # rows q1..q6 of _block's force map that are actuated (q4 may be passive)
    # Blocks of whole geometries x sample slices, at most BLOCK_PAIRS design pairs each.
    per_geo = np.bincount(geo_of, minlength=len(uniq))
    step = max(1, BLOCK_PAIRS // max(1, int(per_geo.max())))
    for s0 in range(0, m, step):
        sl = np.arange(s0, min(m, s0 + step))
        g_per_block = max(1, BLOCK_PAIRS // (sl.size * int(per_geo.max())))
        for g0 in range(0, len(uniq), g_per_block):
            gids = np.arange(g0, min(len(uniq), g0 + g_per_block))
            _block(poses, uniq, gids, sl, geo_of, scale, keep, st, frame, params, a_out, b_out)
    return a_out, b_out


def _block(poses, uniq, gids, sl, geo_of, scale, keep, st, frame, params, a_out, b_out) -> None:
    """One block: geometries ``gids`` x samples ``sl``, written into the designs' rows of the outputs."""
    G, m = gids.size, sl.size
    gidx = np.repeat(gids, m)                      # pair -> geometry
    l1, l2, l3, l6 = (uniq[gidx, i] for i in range(4))
    h = params.ujoint_lever * l6                  # each U-joint's distance from the task point
    half = 0.5 * params.unit_separation
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # (l6, sample) level: one evaluation per distinct pen length in the block
        l6u, l6_of = np.unique(uniq[gids, 3], return_inverse=True)
        pen_idx = np.repeat(np.arange(l6u.size), m)
        pen_s = np.tile(sl, l6u.size)
        hp = params.ujoint_lever * l6u[pen_idx]
        units = [_unit_pen(poses, pen_s, hp, -half, -1.0, params), _unit_pen(poses, pen_s, hp, half, 1.0, params)]
        pair_pen = np.repeat(l6_of.reshape(-1), m) * m + np.tile(np.arange(m), G)
        rows, ok = [], np.ones(G * m, bool)
        for unit, sign, first in zip(units, (-1.0, 1.0), (0, 3)):
            sub = {key: (tuple(v[pair_pen] for v in val) if isinstance(val, tuple) else val[pair_pen])
                   for key, val in unit.items()}
            r, ok_u = _unit_rows(sub, l1, l2, l3, h, sign, params, first, frame)
            rows.append(r)
            ok &= ok_u
        rows = np.concatenate(rows, -2)[:, keep, :] / st          # (P, n, 5): row u = A[:, u] / S_T
        finite = np.all(np.isfinite(rows), axis=(-1, -2))
        safe = np.where(finite[:, None, None], rows, 0.0)
    # designs of these geometries
    pos_of_geo = np.full(int(uniq.shape[0]), -1)
    pos_of_geo[gids] = np.arange(G)
    designs = np.flatnonzero(pos_of_geo[geo_of] >= 0)
    gpos = pos_of_geo[geo_of[designs]]                             # (kd,) geometry position in the block
    pair = (gpos[:, None] * m + np.arange(m)[None, :]).reshape(-1)   # (kd * m,) pair of each design-sample
    mat = safe[pair] * np.repeat(scale[designs], m, axis=0)[:, :, None]   # (kd m, n, 5) = M^T
    gram = np.swapaxes(mat, -1, -2) @ mat                          # M M^T (5 x 5)
    lam = np.linalg.eigvalsh(gram)
    smin = np.sqrt(np.maximum(lam[:, 0], 0.0))                     # a PSD matrix's eigenvalue may round below 0
    smax = np.sqrt(lam[:, -1])
    good = finite[pair]
    smin = np.where(good, smin, np.inf)
    smax = np.where(good, smax, np.inf)
    feas = ok[pair]
    shape = (designs.size, m)
    a_out[np.ix_(designs, sl)] = np.where(feas, smin, np.nan).reshape(shape)
    b_out[np.ix_(designs, sl)] = np.where(feas, smax, np.nan).reshape(shape)
