"""The Stewart platform (``kinematics.stewart``) in one compiled pass: legs, limits, ``K``, ``J``, wrench quantities.

Each point follows the numpy path (``metrics.quantities`` over ``StewartPlatform``) step by step:

=========================  ===========================================  ==================================
step                       formula (numpy)                              here
=========================  ===========================================  ==================================
legs, limits               ``L_i = (o + R p_i) - b_i``, ``q_i = |L_i|``,  the same operations: the same bits;
                           bends ``atan2(|L_i x n|, L_i . n)``          a bend within ``BEND_MARGIN`` of
                           (``inverse``, ``feasible``)                  its limit is handed back
``K``, generators          rows ``[u_i, (R p_i) x u_i]``, ``G = K^T      the same bits
                           diag(t)`` (``inverse_jacobian``)
anisotropic force, moment  ``wrench_slices.slice_max_norm`` on ``G``    ``section.section_point``: the
                                                                        same bits
condition number           ``diag(1, 1, 1, L, L, L) J``'s singular      eigenvalues of the Gram matrix
                           values from its Gram matrix                  of ``K diag(1, 1, 1, L, L, L)^-1``
                           (``wrenches.scaled_condition_number``)       (cyclic Jacobi); hand back above
                                                                        ``FAST_COND_LIMIT``, where numpy
                                                                        calls LAPACK's SVD
isotropic force, moment    ``min_u t_u / |J[rows, u]|``                 ``J`` by LU with partial pivoting
                           (``wrench_facets.slice_inscribed_radius``)   (numpy: LAPACK's)
apparent masses            ``Lambda^-1`` (``dynamics.inverse_spd``: LU  ``stewart_mass.inertia_point``, LU
                           where surely regular), eigenvalues of its    as numpy's test, then
                           force block                                  ``dynamics._eigenvalues_sym3``
isotropic acceleration     ``min_u t_u / |(Lambda J[:, u])[rows]|``     the same sums
=========================  ===========================================  ==================================

A turned platform (an orientation coordinate not 0) is handed back whole: the rotation, its left
Jacobian and the twist's change of coordinates are not compiled here. So are non-finite poses,
points ``J`` is ill-conditioned at (the scaled condition above ``FAST_COND_LIMIT``), matrices off
``SAFE_SCALE`` and every step's own "hard" case: those points get the numpy path's values exactly.
The tolerances between the two paths are derived in ``tests/metrics/test_kernel_stewart.py``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE, SURE_REGULAR

from . import COLUMNS
from .dynamics import _eigenvalues_sym3
from .jit import jit, twins
from .section import section_point
from .square3 import blank
from .stewart_mass import SCRATCH as MASS_SCRATCH
from .stewart_mass import inertia_point

EPS = 2.220446049250313e-16
_EPS2 = EPS * EPS
#: Two libm-grade ``atan2`` results (numpy's SIMD loop, libm here) of the same arguments are each
#: within 1 ulp of the exact angle, so within 2 ulps of each other; an angle is at most pi, whose
#: ulp is ``2 eps``: they differ by at most ``4 eps pi``. A bend closer than twice that to its
#: limit could be labelled otherwise than numpy labels it: handed back.
BEND_MARGIN = 8.0 * EPS * math.pi
_COND, _INV_COND = COLUMNS.index("condition_number"), COLUMNS.index("inverse_condition_number")
_ISO_F, _ANI_F = COLUMNS.index("isotropic_force"), COLUMNS.index("anisotropic_force")
_ISO_M, _ANI_M = COLUMNS.index("isotropic_moment"), COLUMNS.index("anisotropic_moment")
_AM_MIN, _AM_MAX = COLUMNS.index("apparent_mass_min"), COLUMNS.index("apparent_mass_max")
_ACC = COLUMNS.index("isotropic_acceleration")
_SCALE_LO, _SCALE_HI = SAFE_SCALE
#: ``wrench_facets._inscribed_radius``'s range of a plain norm (outside it numpy redoes it scaled).
_DEN_LO, _DEN_HI = 2.0 ** -450, 2.0 ** 500
#: Jacobi sweeps after which ``_gram_extremes`` gives up (hands the point back); 6 x 6 takes 5-8.
_SWEEPS = 30
#: Points per ``prange`` task, each with one scratch buffer.
BLOCK = 64
# ``pack``'s geometry: base joints (6 x 3), platform joints (6 x 3), then scalars.
_B, _P = 0, 18
_MIN, _MAX, _BASE_LIM, _TOP_LIM, _LEN, _KEPS_F, _KEPS_M, _BOX, _SECTION = range(36, 45)
# Scratch offsets (6 x 6 blocks), then ``inertia_point``'s, then the sections'.
_KM, _JM, _LU, _GR, _GP, _LAM, _MOB = (36 * k for k in range(7))
_EYE = 7 * 36
_MSC = _EYE + 9
_SEC = _MSC + MASS_SCRATCH


#: The task coordinates of the platform's orientation (``StewartPlatform.task_names``).
ORIENTATION = ("rx", "ry", "rz")


def covers(grid) -> bool:
    """Whether the kernel computes a grid's points itself: the platform at zero orientation throughout.

    A turned platform's points all go back to numpy, one chunk at a time on the calling thread, where
    the numpy path spreads its chunks over the cores: such a map takes the numpy path whole
    (``map_chunks.ChunkWork.plan``).

    Parameters
    ----------
    grid : GridSpec
        The map's grid (each task coordinate an axis or fixed).

    Returns
    -------
    bool
    """
    fixed = dict(grid.fixed)
    return not set(grid.axes) & set(ORIENTATION) and all(fixed.get(name, 0.0) == 0.0 for name in ORIENTATION)


def pack(mechanism) -> tuple:
    """The model's geometry and the two wrench slices' tables, as the kernel reads them.

    Parameters
    ----------
    mechanism : StewartPlatform
        The model.

    Returns
    -------
    tuple
        ``geometry`` (45,) float64: ``b_i`` and ``p_i`` row by row, the leg range, the two bend
        limits, ``characteristic_length``, the slices' ``k eps``, ``1 + VERTEX_TOL`` and the
        sections' scratch length; then ``wrench_slices._section_kernel_plan``'s eight tables of the
        force slice (rows 0-2) and of the moment slice (rows 3-5).
    """
    from ..wrench_slices import VERTEX_TOL, _section_kernel_plan
    from ..wrenches import characteristic_length, force_rows, moment_rows

    p = mechanism.params
    force, size_f, keps_f = _section_kernel_plan(6, 6, tuple(force_rows(mechanism)))
    moment, size_m, keps_m = _section_kernel_plan(6, 6, tuple(moment_rows(mechanism)))
    geometry = np.array([*mechanism.base_joints().ravel(), *mechanism.platform_joints().ravel(), p.min_leg,
                         p.max_leg, p.base_joint_limit, p.platform_joint_limit, characteristic_length(mechanism),
                         keps_f, keps_m, 1.0 + VERTEX_TOL, max(size_f, size_m)], dtype=np.float64)
    return (geometry, *force, *moment)


def pack_mass(mechanism) -> np.ndarray:
    """``stewart_mass.pack_mass``'s arrays in one (229,) float64 array (``_mass_arrays`` unpacks it).

    Parameters
    ----------
    mechanism : StewartPlatform
        With a mass model.

    Returns
    -------
    ndarray, shape (229,)
    """
    from .stewart_mass import pack_mass as arrays

    return np.concatenate([np.ravel(a) for a in arrays(mechanism)]).astype(np.float64)


#: ``pack_mass``' length: base, platform joints and tangents (6 x 3 each), 13 masses, centres (13 x 3),
#: tensors (13 x 3 x 3), 6 rotor inertias.
_MASS_SIZE = 3 * 18 + 13 + 39 + 117 + 6


@jit(inline=True)
def _mass_arrays(mp):
    """``pack_mass``' array back as ``stewart_mass.pack_mass``'s seven."""
    return (mp[0:18].reshape(6, 3), mp[18:36].reshape(6, 3), mp[36:54].reshape(6, 3), mp[54:67],
            mp[67:106].reshape(13, 3), mp[106:223].reshape(13, 3, 3), mp[223:229])


@jit()
def _inverse6(a, lu, inv):
    """``inv = a^-1`` (6 x 6) by LU with partial pivoting (``lu`` scratch); ``(ok, det)``, ok False at a zero pivot."""
    for r in range(6):
        for c in range(6):
            lu[r, c] = a[r, c]
            inv[r, c] = 1.0 if r == c else 0.0
    det = 1.0
    for k in range(6):
        piv, big = k, abs(lu[k, k])
        for r in range(k + 1, 6):
            if abs(lu[r, k]) > big:
                piv, big = r, abs(lu[r, k])
        if not big > 0.0:
            return False, 0.0
        if piv != k:
            det = -det
            for c in range(6):
                lu[k, c], lu[piv, c] = lu[piv, c], lu[k, c]
                inv[k, c], inv[piv, c] = inv[piv, c], inv[k, c]
        det *= lu[k, k]
        for r in range(k + 1, 6):
            f = lu[r, k] / lu[k, k]
            for c in range(k + 1, 6):
                lu[r, c] -= f * lu[k, c]
            for c in range(6):
                inv[r, c] -= f * inv[k, c]
    for c in range(6):                      # back substitution, each right-hand side
        for r in range(5, -1, -1):
            acc = inv[r, c]
            for j in range(r + 1, 6):
                acc -= lu[r, j] * inv[j, c]
            inv[r, c] = acc / lu[r, r]
    return True, det


@jit()
def _gram_extremes(a):
    """``(hard, largest, smallest)`` eigenvalue of a symmetric positive definite 6 x 6 ``a`` (overwritten).

    Cyclic Jacobi (Rutishauser's rotation, as ``dynamics._jacobi_sym3``): each rotation is backward
    stable, and an off-diagonal entry is dropped once below ``eps sqrt(a_pp a_qq)``, which moves no
    eigenvalue of a positive definite matrix by more than ``eps`` relative to it (Demmel and
    Veselic). Hard where a diagonal entry is not positive or the sweeps do not converge.
    """
    for _ in range(_SWEEPS):
        for d in range(6):
            if not a[d, d] > 0.0:
                return True, 0.0, 0.0
        rotated = False
        for p in range(5):
            for q in range(p + 1, 6):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                if apq * apq <= _EPS2 * (a[p, p] * a[q, q]):    # |a_pq| <= eps sqrt(a_pp a_qq), squared
                    a[p, q] = 0.0
                    a[q, p] = 0.0
                    continue
                rotated = True
                app, aqq = a[p, p], a[q, q]
                theta = (aqq - app) / (2.0 * apq)
                if abs(theta) > 1e150:      # theta^2 would overflow: t = 1 / (2 theta) to working precision
                    t = 0.5 / theta
                else:
                    t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                tau = s / (1.0 + c)
                a[p, p] = app - t * apq
                a[q, q] = aqq + t * apq
                a[p, q] = 0.0
                a[q, p] = 0.0
                for r in range(6):
                    if r != p and r != q:
                        arp, arq = a[r, p], a[r, q]
                        a[r, p] = arp - s * (arq + tau * arp)
                        a[p, r] = a[r, p]
                        a[r, q] = arq + s * (arp - tau * arq)
                        a[q, r] = a[r, q]
        if not rotated:
            big, small = a[0, 0], a[0, 0]
            for d in range(1, 6):
                big = max(big, a[d, d])
                small = min(small, a[d, d])
            return False, big, small
    return True, 0.0, 0.0


@jit(inline=True)
def _column_radius(mat, rows0, t):
    """``(hard, min_u t_u / |mat[rows0:rows0 + 3, u]|)`` (``wrench_facets._inscribed_radius``'s plain norms)."""
    radius = math.inf
    for u in range(6):
        den = mat[rows0, u] * mat[rows0, u]
        den += mat[rows0 + 1, u] * mat[rows0 + 1, u]
        den += mat[rows0 + 2, u] * mat[rows0 + 2, u]
        den = math.sqrt(den)
        if not (den > _DEN_LO and den < _DEN_HI):
            return True, 0.0
        radius = min(radius, t[u] / den)
    return False, radius


@jit(inline=True)
def _slice_max(kmat, t, gp, par, moment, sec):
    """The force (``moment`` False) or moment slice's largest norm of ``G = K^T diag(t)`` (``section_point``)."""
    geo = par[0]
    for r in range(6):
        for u in range(6):
            gp[r * 6 + u] = kmat[u, r] * t[u]
    if moment:
        return section_point(gp, 6, par[9], par[10], par[11], par[12], par[13], par[14], par[15], par[16],
                             geo[_KEPS_M], geo[_BOX], sec)
    return section_point(gp, 6, par[1], par[2], par[3], par[4], par[5], par[6], par[7], par[8], geo[_KEPS_F],
                         geo[_BOX], sec)


@jit(inline=True)
def _point(x, par, t, i, feasible, joints, out, bottleneck, singularity, want_sv, want_columns, want_vertices,
           mass, want_mass, want_acceleration, kmat, jmat, lu, gram, gp, lam, mob, eye, msc, sec):
    """Point ``i``: True to hand it back to the numpy path. Every output starts infeasible (``blank``).

    ``mass``: ``_mass_arrays``; ``kmat`` ... ``sec``: the block's scratch (``_run``), overwritten.
    """
    blank(i, feasible, joints, out, bottleneck, singularity, True)
    for c in range(6):
        if not math.isfinite(x[i, c]):
            return True
    if x[i, 3] != 0.0 or x[i, 4] != 0.0 or x[i, 5] != 0.0:
        return True                         # a turned platform: numpy
    geo = par[0]
    o0, o1, o2 = x[i, 0], x[i, 1], x[i, 2]
    # -- StewartPlatform.inverse and feasible at R = I (R p_i = p_i, the platform normal e_z)
    ok, near = True, False
    for leg in range(6):
        a0, a1, a2 = geo[_P + 3 * leg], geo[_P + 3 * leg + 1], geo[_P + 3 * leg + 2]
        l0 = o0 + a0 - geo[_B + 3 * leg]
        l1 = o1 + a1 - geo[_B + 3 * leg + 1]
        l2 = o2 + a2 - geo[_B + 3 * leg + 2]
        q = math.sqrt(0.0 + l0 * l0 + l1 * l1 + l2 * l2)       # vector_rows.dot's order
        joints[i, leg] = q
        if not (math.isfinite(q) and q >= geo[_MIN] and q <= geo[_MAX]):
            ok = False
            continue
        # vector_rows.angle_between(L, e_z): the same products, so the same atan2 arguments.
        c0, c1, c2 = l1 * 1.0 - l2 * 0.0, l2 * 0.0 - l0 * 1.0, l0 * 0.0 - l1 * 0.0
        bend = math.atan2(math.sqrt(0.0 + c0 * c0 + c1 * c1 + c2 * c2), 0.0 + l0 * 0.0 + l1 * 0.0 + l2 * 1.0)
        for limit in (geo[_BASE_LIM], geo[_TOP_LIM]):
            if abs(bend - limit) <= BEND_MARGIN:
                near = True
            elif bend > limit:
                ok = False
        u0, u1, u2 = l0 / q, l1 / q, l2 / q
        kmat[leg, 0], kmat[leg, 1], kmat[leg, 2] = u0, u1, u2
        kmat[leg, 3], kmat[leg, 4], kmat[leg, 5] = a1 * u2 - a2 * u1, a2 * u0 - a0 * u2, a0 * u1 - a1 * u0
    if not ok:
        for leg in range(6):
            joints[i, leg] = math.nan
        return False
    if near:
        return True
    feasible[i] = True
    if want_vertices:
        force = _slice_max(kmat, t, gp, par, False, sec)
        moment = _slice_max(kmat, t, gp, par, True, sec)
        if not (math.isfinite(force) and math.isfinite(moment)):
            return True
        out[_ANI_F, i], out[_ANI_M, i] = force, moment
    need_j = want_columns or want_acceleration
    if want_sv or need_j:
        # cond(diag(1, 1, 1, L, L, L) J) = cond(K_s), K_s = K diag(1, 1, 1, L, L, L)^-1: its Gram matrix.
        # K_s in jmat (free until J), then its Gram matrix.
        length = geo[_LEN]
        for u in range(6):
            for a in range(6):
                jmat[u, a] = kmat[u, a] if a < 3 else kmat[u, a] / length
        for a in range(6):
            for b in range(a, 6):
                acc = 0.0
                for u in range(6):
                    acc += jmat[u, a] * jmat[u, b]
                gram[a, b] = acc
                gram[b, a] = acc
        for d in range(6):
            if not (gram[d, d] > _SCALE_LO and gram[d, d] < _SCALE_HI):
                return True
        hard, big, small = _gram_extremes(gram)
        if hard:
            return True
        cond = math.sqrt(big / small)
        if not cond <= FAST_COND_LIMIT:
            return True
        out[_COND, i], out[_INV_COND, i] = cond, 1.0 / cond
    if need_j:
        regular, _ = _inverse6(kmat, lu, jmat)
        if not regular:
            return True
    if want_columns:
        hard, force = _column_radius(jmat, 0, t)
        if hard:
            return True
        hard, moment = _column_radius(jmat, 3, t)
        if hard:
            return True
        out[_ISO_F, i], out[_ISO_M, i] = force, moment
    if not (want_mass or want_acceleration):
        return False
    # -- dynamics.task_inertia (R = J_l = I, so per twist as it is), then inverse_spd's LU branch
    base, platform, tangent, masses, com, tensors, rotors = mass
    inertia_point(o0, o1, o2, eye, eye, base, platform, tangent, masses, com, tensors, rotors, lam, msc)
    tr = 0.0
    for d in range(6):
        tr += lam[d, d]
    for r in range(6):
        for c in range(6):
            if not math.isfinite(lam[r, c]):
                return True
    if not (tr > _SCALE_LO and tr < _SCALE_HI and tr / 6.0 > _SCALE_LO and tr / 6.0 < _SCALE_HI):
        return True
    regular, det = _inverse6(lam, lu, mob)
    if not (regular and det > SURE_REGULAR * 6.0 * EPS * tr ** 6):
        return True
    if want_mass:
        # 0.5 (inv + inv^T) on the force block, then its eigenvalues (dynamics.apparent_mass_range).
        w00, w11, w22 = mob[0, 0], mob[1, 1], mob[2, 2]
        w01, w02, w12 = 0.5 * (mob[0, 1] + mob[1, 0]), 0.5 * (mob[0, 2] + mob[2, 0]), 0.5 * (mob[1, 2] + mob[2, 1])
        hard, e1, e2, e3 = _eigenvalues_sym3(w00, w01, w02, w11, w12, w22)
        if hard or not (e3 > 3.0 * EPS * max(abs(e1), max(abs(e2), abs(e3)))):
            return True
        out[_AM_MIN, i], out[_AM_MAX, i] = 1.0 / e1, 1.0 / e3
    if want_acceleration:
        # Slab normals Lambda J[:, u] (dynamics.acceleration_facets), their force rows' norms.
        radius = math.inf
        for u in range(6):
            den = 0.0
            for a in range(3):
                acc = 0.0
                for m in range(6):
                    acc += jmat[m, u] * lam[m, a]
                den += acc * acc
            den = math.sqrt(den)
            if not (den > _DEN_LO and den < _DEN_HI):
                return True
            radius = min(radius, t[u] / den)
        out[_ACC, i] = radius
    return False


def _run(x, par, t, steps, feasible, joints, out, bottleneck, singularity, fallback,
         want_sv, want_columns, want_vertices,
         mp, want_mass, want_acceleration, speeds, want_velocity):
    """Every point of ``x`` (k, 6) into the outputs (``FusedKernel.run``): over the cores in ``run_parallel``,
    on the calling thread in ``run_serial`` (``jit.twins``); ``BLOCK`` points share one scratch buffer.
    """
    n = x.shape[0]
    size = _SEC + int(par[0][_SECTION])
    # Without the masses ``mp`` is a placeholder (``np.zeros(1)``, also in ``kernels._load``'s first call,
    # whose points are not feasible): zeros of ``pack_mass``' length stand in, never read.
    mass = _mass_arrays(mp if mp.shape[0] == _MASS_SIZE else np.zeros(_MASS_SIZE))
    for block in prange((n + BLOCK - 1) // BLOCK):
        work = np.empty(size)
        for d in range(9):
            work[_EYE + d] = 1.0 if d % 4 == 0 else 0.0
        # The views once a block (each one a reference count).
        kmat, jmat = work[_KM:_KM + 36].reshape(6, 6), work[_JM:_JM + 36].reshape(6, 6)
        lu, gram = work[_LU:_LU + 36].reshape(6, 6), work[_GR:_GR + 36].reshape(6, 6)
        lam, mob = work[_LAM:_LAM + 36].reshape(6, 6), work[_MOB:_MOB + 36].reshape(6, 6)
        gp, eye = work[_GP:_GP + 36], work[_EYE:_EYE + 9].reshape(3, 3)
        msc, sec = work[_MSC:_MSC + MASS_SCRATCH], work[_SEC:]
        for i in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
            fallback[i] = _point(x, par, t, i, feasible, joints, out, bottleneck, singularity, want_sv,
                                 want_columns, want_vertices, mass, want_mass, want_acceleration, kmat, jmat, lu,
                                 gram, gp, lam, mob, eye, msc, sec)


run_parallel, run_serial = twins(_run, "run", allocates=True)
