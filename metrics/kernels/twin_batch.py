"""The Twin-Pantograph's force GII per (design, sample), compiled: ``metrics.design.twin_batch``'s pass.

One pass over (geometry, sample) items, a geometry being ``(l1, l2, l3, l6)`` and its designs the
run of consecutive designs that share it (Table VII: the 26 waist torques ``Q1``). Per item, in
scalars: the pen frame ``R = (a, p, b)`` (``kinematics.rotations.tilt_matrix``'s Rodrigues form),
each unit's waist, plane frame, U-joint bend, five-bar IK and its three force-map rows (the
closed form of ``metrics.design.twin_batch``'s module doc, in the numpy reference's order of
operations), the limits; then per design the scaled rows ``M^T = (A / S_T) S_J``, the Gram
matrix ``G = M M^T`` (5 x 5) and its extreme eigenvalues by cyclic Jacobi (``_jacobi``), no
LAPACK, ``LANES`` Gram matrices side by side. ``sigma_min = sqrt(max(lambda_min, 0))``,
``sigma_max = sqrt(lambda_max)``.

A pair's value depends on the pair alone: every item is computed by the same scalar code
whatever the call, the chunking or the thread count (no reduction across items), so the
``prange`` build (``run_parallel``) and the serial one (``run_serial``) give the same bits. In the
lanes, a lane whose entry ``a_pq`` is negligible gets ``t = 0``, ``c = 1``, ``s = 0``: every update
``c x - s y`` then gives ``x`` back exactly and the diagonal ``a_pp - t a_pq`` is ``a_pp``, so a lane
that has converged stays as it is while its neighbours rotate on, and each lane ends with the bits
it would get alone.

Accuracy of the Jacobi (a symmetric ``G``; positive semidefinite here). ``G`` is first scaled by
the power of two ``2^-e`` that brings its trace into [0.5, 1) (exact, and undone exactly), so no
square in a rotation overflows or underflows for traces within the normal range. A rotation
annihilating ``a_pq`` (``_rotate``) computes ``t`` with a relative error of about 5 eps (a
square root, a sum, a quotient), ``c`` and ``s`` within about 2 eps of an exactly orthogonal
pair (``c^2 (1 + t^2)`` is 1 to 3 eps whatever ``t``'s error), and each updated entry as two
products and a sum (2 eps of ``|c x| + |s y|``). So the computed matrix after the rotation is
the exact orthogonal similarity of ``A + E_k`` with ``|E_k|_F <= GAMMA eps |A|_F``, ``GAMMA =
12`` covering the non-orthogonality on both sides (2 x 2), the updates (2) and ``a_pq`` set to
zero where ``t``'s error left ``5 eps |a_pq|`` (5), with a margin (Wilkinson, *The Algebraic
Eigenvalue Problem*, ch. 3, the same analysis, first order in eps). An off-diagonal entry is
dropped (set to zero without a rotation) once ``|a_pq| <= eps tr``: each such drop is a
symmetric perturbation of Frobenius norm at most ``sqrt(2) eps tr``. The Frobenius norm of a
positive semidefinite ``G`` is at most its trace, so, by Weyl's theorem, every computed
eigenvalue is within

    ``(GAMMA R + 1.5 D) eps tr(G)``     (R rotations applied, D nonzero entries dropped)

of the exact eigenvalue of ``G`` (``tr(G) <= 5 lambda_max``; ``extremes`` returns R and D). That
is the form of LAPACK's ``eigvalsh`` (``p(n) eps |G|``) with a constant linear in the rotations;
it is a worst case, every rounding adding up: the errors measured against mpmath are 2 eps
``tr(G)`` at most, 1.7 % of it (``tests/metrics/test_twin_batch_kernel.py``). Convergence is
quadratic: a 5 x 5 takes 4 to 6 sweeps of 10 planes (at most 56 rotations and 11 drops on
200,000 Gram matrices of random 5 x 6 matrices). ``SWEEPS`` caps them, and no matrix met the
cap; the bound holds only for a converged lane (its last sweep rotated nothing: every
off-diagonal entry is then below ``eps tr`` and dropped), so a lane that meets the cap has no
result here: ``run`` writes ``HANDED_BACK`` at its pair, which the caller recomputes with LAPACK
(``metrics.design.twin_batch``), and ``extremes`` writes ``nan``. Added to the Gram matrix's own
rounding (``metrics.design.twin_batch``: ``eps sigma_max^2``, so ``eps kappa^2`` relative in
``sigma_min``), nothing in that analysis changes but the constant.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from .jit import jit, twins

EPS = 2.220446049250313e-16
#: Sweeps after which ``_jacobi`` stops (a 5 x 5 converges in 4 to 6, see the module doc); the
#: default of ``lane_buffer``, which hands it to ``_jacobi`` (tests lower it to meet the cap).
SWEEPS = 10
#: ``run``'s value at a pair whose Jacobi met the cap (no singular value is negative): the caller's to recompute.
HANDED_BACK = -1.0
#: Plane visits at most (``SWEEPS`` sweeps of 10 planes): ``R + D`` of the module doc's bound.
MAX_ROTATIONS = 10 * SWEEPS
#: The per-rotation constant of the module doc's bound.
GAMMA = 12.0
#: ``params`` layout (``pack``): half the unit separation, the U-joint lever, the U-joint limit,
#: then the lower and the upper limits of q1..q6.
_HALF, _LEVER, _BEND, _LOWER, _UPPER = 0, 1, 2, 3, 9
_SLACK = 8.0 * EPS                 # as TwinPantograph: cosines a few ulps beyond 1 are clipped
_TWO_PI = 2.0 * np.pi
_SMALL = 1e-4                      # kinematics.rotations._SMALL: series below it


def pack(params) -> np.ndarray:
    """The model's parameters the kernel reads, ``params`` layout above.

    Parameters
    ----------
    params : TwinPantographParams

    Returns
    -------
    ndarray, shape (15,)
    """
    return np.array([0.5 * params.unit_separation, params.ujoint_lever, params.ujoint_limit,
                     *params.lower_limits[:6], *params.upper_limits[:6]], np.float64)


@jit()
def _angle_in(angle, lower, upper):
    """``kinematics.angles.wrap_into`` followed by the limit check (as the numpy reference)."""
    shifted = angle - _TWO_PI * math.floor((angle - lower) / _TWO_PI)
    return shifted >= lower and shifted <= upper


@jit()
def _pen_frame(rx, rz):
    """Columns ``a, p, b`` of ``tilt_matrix((rx, rz))`` = ``I + A K + B K^2``, ``K = [(rx, 0, rz)]x``."""
    theta = math.sqrt(rx * rx + rz * rz)
    if theta < _SMALL:
        t2 = theta * theta
        sa = 1.0 - t2 / 6.0 + t2 * t2 / 120.0
        sb = 0.5 - t2 / 24.0 + t2 * t2 / 720.0
    else:
        sa = math.sin(theta) / theta
        sb = (1.0 - math.cos(theta)) / (theta * theta)
    # K^2 = [[-rz^2, 0, rz rx], [0, -rz^2 - rx^2, 0], [rx rz, 0, -rx^2]]
    a = (1.0 + sb * -(rz * rz), sa * rz, sb * (rx * rz))
    p = (sa * -rz, 1.0 + sb * (-(rz * rz) - rx * rx), sa * rx)
    b = (sb * (rz * rx), sa * -rx, 1.0 + sb * -(rx * rx))
    return a, p, b


@jit()
def _unit(cx, cy, cz, a, p, b, h, y0, sign, l1, l2, l3, prm, first, end_effector):
    """One unit at one sample: ``(ok, row0, row1, row2)``, its waist and two shoulder rows (5 each).

    ``sign`` is ``-1`` for unit A (its U-joint at ``centre - h p``), ``+1`` for B; ``first`` its
    waist's joint (0 or 3). The formulas and their order are ``_unit_pen`` and ``_unit_rows``'s
    where they decide feasibility (the angles and the bend); the sines and cosines of the waist
    and shoulder angles come from the same quantities algebraically (a few ulps from libm's).
    """
    sh = sign * h
    u = cx + sh * p[0]
    dy = (cy + sh * p[1]) - y0
    dz = cz + sh * p[2]
    psi = math.atan2(-dy, dz)
    w = math.hypot(dy, dz)
    if w > 0.0:                       # sin and cos of psi, without two libm calls
        s, c = -dy / w, dz / w
    else:
        s, c = math.sin(psi), math.cos(psi)
    pn = p[1] * c + p[2] * s
    x0, x1, x2 = p[1] * s - p[2] * c, -(p[0] * s), p[0] * c
    bend = math.atan2(math.sqrt(x0 * x0 + x1 * x1 + x2 * x2), pn)
    ok = bend <= prm[_BEND] and _angle_in(psi, prm[_LOWER + first], prm[_UPPER + first])
    # e_x, e_r = (0, -s, c) and n = (0, -c, -s) on the pen frame's axes
    ex = (a[0], p[0], b[0])
    er = (-s * a[1] + c * a[2], -s * p[1] + c * p[2], -s * b[1] + c * b[2])
    nn = (-c * a[1] - s * a[2], -c * p[1] - s * p[2], -c * b[1] - s * b[2])
    lever = sign * h
    row0 = _row(0.0, 1.0 / w, ex, nn, s, c, lever, end_effector, True)
    ok1, row1 = _shoulder(u, w, -0.5 * l1, 1.0, l2, l3, prm[_LOWER + first + 1], prm[_UPPER + first + 1], ex, er,
                          s, c, lever, end_effector)
    ok2, row2 = _shoulder(u, w, 0.5 * l1, -1.0, l2, l3, prm[_LOWER + first + 2], prm[_UPPER + first + 2], ex, er,
                          s, c, lever, end_effector)
    return ok and ok1 and ok2, row0, row1, row2


@jit()
def _shoulder(u, w, sx, branch, l2, l3, lower, upper, ex, er, s, c, lever, end_effector):
    """A shoulder's five-bar IK (elbow ``branch``), its limit and its row: ``(ok, row)``."""
    d0 = u - sx
    rho = math.hypot(d0, w)
    cos_e = (l2 * l2 + rho * rho - l3 * l3) / (2.0 * l2 * rho)
    ok = abs(cos_e) <= 1.0 + _SLACK
    cb = min(max(cos_e, -1.0), 1.0)
    theta = math.atan2(w, d0) + branch * math.acos(cb)
    ok = ok and _angle_in(theta, lower, upper)
    # cos and sin of theta = alpha + branch beta by the angle sum, without two libm calls:
    # cos alpha = d0 / rho, sin alpha = w / rho, cos beta = cb, sin beta = sqrt((1 - cb)(1 + cb))
    sb = math.sqrt(max((1.0 - cb) * (1.0 + cb), 0.0))
    ca, sa = d0 / rho, w / rho
    ct = ca * cb - branch * (sa * sb)
    st = sa * cb + branch * (ca * sb)
    dist0 = u - (sx + l2 * ct)
    dist1 = w - (0.0 + l2 * st)
    denom = l2 * (dist0 * -st + dist1 * ct)
    return ok, _row(dist0 / denom, dist1 / denom, ex, er, s, c, lever, end_effector, False)


@jit()
def _row(alpha, beta, ex, basis, s, c, lever, end_effector, waist):
    """The force-map row of ``g = alpha e_x + beta basis``: ``(f, lever g.b, -lever g.a)``."""
    ga = alpha * ex[0] + beta * basis[0]
    gb = alpha * ex[2] + beta * basis[2]
    if end_effector:
        f0, f1, f2 = ga, alpha * ex[1] + beta * basis[1], gb
    elif waist:                       # base frame: g itself; n = (0, -c, -s)
        f0, f1, f2 = 0.0, -c * beta, -s * beta
    else:                             # e_r = (0, -s, c)
        f0, f1, f2 = alpha, -s * beta, c * beta
    return f0, f1, f2, lever * gb, -lever * ga


@jit()
def _finite(r):
    return (math.isfinite(r[0]) and math.isfinite(r[1]) and math.isfinite(r[2]) and math.isfinite(r[3])
            and math.isfinite(r[4]))


@jit()
def _scaled(r, st, w):
    """``(r / S_T) w``: a row of ``M^T``."""
    return (r[0] / st[0] * w, r[1] / st[1] * w, r[2] / st[2] * w, r[3] / st[3] * w, r[4] / st[4] * w)


@jit()
def _outer_add(g, y):
    """``g + y y^T``, both as the upper triangle (15 entries, row by row)."""
    return (g[0] + y[0] * y[0], g[1] + y[0] * y[1], g[2] + y[0] * y[2], g[3] + y[0] * y[3], g[4] + y[0] * y[4],
            g[5] + y[1] * y[1], g[6] + y[1] * y[2], g[7] + y[1] * y[3], g[8] + y[1] * y[4],
            g[9] + y[2] * y[2], g[10] + y[2] * y[3], g[11] + y[2] * y[4],
            g[12] + y[3] * y[3], g[13] + y[3] * y[4], g[14] + y[4] * y[4])


#: Matrices ``_jacobi`` diagonalises side by side: numba (LLVM's loop vectorizer; its SLP vectorizer
#: is off) turns a lane loop into AVX2 from 8 lanes on, not 4. 0.32 us a matrix against 0.87 with 4.
LANES = 8
#: Rows of a lane buffer (``_jacobi``): the 15 entries of the upper triangle, row by row, then the
#: square of a negligible entry's bound, the rotations applied, the power of two that undoes the
#: scaling, the lane's pair (design, sample) as floats (exact below 2^53), the nonzero entries
#: dropped, the rotations applied before the last sweep (the lane converged if they are all).
#: After the rows, one more entry: the sweeps' cap (``lane_buffer``).
_UP, _ROT, _SCALE, _D, _J, _DROP, _LAST = 15, 16, 17, 18, 19, 20, 21
_ROWS = 22
_EPS2 = EPS * EPS


@jit(inline=True)
def _rotate(a, app, aqq, apq, r0p, r0q, r1p, r1q, r2p, r2q):
    """One Jacobi rotation in plane (p, q) of every lane of ``a`` (rows: entries' positions).

    A lane whose ``a_pq`` is negligible (module doc) gets ``t = 0``: ``c = 1``, ``s = 0``, which
    leaves every entry of it as it was (``x - 0 y = x``), so a lane's result is the one it gets
    alone, whatever the other lanes need. Entries are at most about 1 (the trace scaled into
    [0.5, 1)), so no square overflows.
    """
    for lane in range(LANES):
        p, q, pq = a[app * LANES + lane], a[aqq * LANES + lane], a[apq * LANES + lane]
        d = q - p
        e = 2.0 * pq
        t = e / (d + math.copysign(math.sqrt(d * d + e * e), d))     # tan of the angle, |t| <= 1
        drop = pq * pq <= a[_UP * LANES + lane]
        t = 0.0 if drop else t
        c = 1.0 / math.sqrt(1.0 + t * t)
        s = t * c
        a[app * LANES + lane] = p - t * pq
        a[aqq * LANES + lane] = q + t * pq
        a[apq * LANES + lane] = 0.0
        x, y = a[r0p * LANES + lane], a[r0q * LANES + lane]
        a[r0p * LANES + lane], a[r0q * LANES + lane] = c * x - s * y, s * x + c * y
        x, y = a[r1p * LANES + lane], a[r1q * LANES + lane]
        a[r1p * LANES + lane], a[r1q * LANES + lane] = c * x - s * y, s * x + c * y
        x, y = a[r2p * LANES + lane], a[r2q * LANES + lane]
        a[r2p * LANES + lane], a[r2q * LANES + lane] = c * x - s * y, s * x + c * y
        a[_ROT * LANES + lane] += 0.0 if drop else 1.0
        a[_DROP * LANES + lane] += 1.0 if drop and pq != 0.0 else 0.0


@jit()
def _load(a, lane, g):
    """Put a symmetric 5 x 5 (``g``: its upper triangle, 15 entries) in ``a``'s ``lane``, scaled.

    The scale is the power of two ``2^-e`` that brings the trace into [0.5, 1) (exact); row
    ``_UP`` keeps the square of the bound below which an off-diagonal entry is dropped
    (``(eps tr)^2``), and
    the factor ``2^e`` to row ``_SCALE``. A trace that is not positive and finite leaves the
    lane zero (converged at once), with the factor 0 (a zero matrix) or ``nan``.
    """
    tr = g[0] + g[5] + g[9] + g[12] + g[14]
    ok = tr > 0.0 and tr < np.inf
    e = math.frexp(tr)[1] if ok else 0
    down = math.ldexp(1.0, -e) if ok else 0.0
    for i in range(15):
        a[i * LANES + lane] = g[i] * down
    a[_UP * LANES + lane] = _EPS2 * (tr * down) * (tr * down) if ok else 0.0
    a[_ROT * LANES + lane] = 0.0
    a[_DROP * LANES + lane] = 0.0
    a[_SCALE * LANES + lane] = math.ldexp(1.0, e) if ok else (0.0 if tr == 0.0 else np.nan)


@jit()
def _jacobi(a):
    """Cyclic Jacobi on every lane of ``a`` until none rotates (at most the cap's sweeps).

    The ten planes of a sweep in a round-robin order: the two rotations of a round touch
    disjoint planes, so their angles are independent and the processor overlaps them. Row
    ``_LAST`` keeps each lane's rotations before the last sweep run (``_converged``).
    """
    before = 0.0
    for _ in range(int(a[_ROWS * LANES])):
        for lane in range(LANES):
            a[_LAST * LANES + lane] = a[_ROT * LANES + lane]
        _rotate(a, 5, 14, 8, 1, 4, 6, 11, 7, 13)
        _rotate(a, 9, 12, 10, 2, 3, 6, 7, 11, 13)
        _rotate(a, 0, 9, 2, 1, 6, 3, 10, 4, 11)
        _rotate(a, 12, 14, 13, 3, 4, 7, 8, 10, 11)
        _rotate(a, 5, 12, 7, 1, 3, 6, 10, 8, 13)
        _rotate(a, 0, 14, 4, 1, 8, 2, 11, 3, 13)
        _rotate(a, 9, 14, 11, 2, 4, 6, 8, 10, 13)
        _rotate(a, 0, 5, 1, 2, 6, 3, 7, 4, 8)
        _rotate(a, 0, 12, 3, 1, 7, 2, 10, 4, 13)
        _rotate(a, 5, 9, 6, 1, 2, 7, 10, 8, 11)
        done = 0.0
        for lane in range(LANES):
            done += a[_ROT * LANES + lane]
        if done == before:
            break
        before = done


@jit()
def _converged(a, lane):
    """Whether the lane's last sweep rotated nothing (else it met the cap: no bound holds)."""
    return a[_ROT * LANES + lane] == a[_LAST * LANES + lane]


@jit()
def _extremes(a, lane):
    """``(lambda_min, lambda_max)`` of a diagonalised lane, its scaling undone."""
    up = a[_SCALE * LANES + lane]
    d0, d1, d2, d3, d4 = (a[0 * LANES + lane], a[5 * LANES + lane], a[9 * LANES + lane], a[12 * LANES + lane],
                          a[14 * LANES + lane])
    lo = min(min(min(d0, d1), min(d2, d3)), d4)
    hi = max(max(max(d0, d1), max(d2, d3)), d4)
    return lo * up, hi * up


@jit()
def extremes(mats, out, rotations, drops, a):
    """The extreme eigenvalues of each matrix, ``LANES`` at a time: ``out[i] = (lambda_min, lambda_max)``.

    The production routine (``_load``, ``_jacobi``, ``_extremes``), for tests and benchmarks. A
    matrix whose Jacobi met the cap (``lane_buffer``'s ``sweeps``) gets ``nan``.

    Parameters
    ----------
    mats : ndarray, shape (N, 5, 5)
        Symmetric (the upper triangle is read).
    out : ndarray, shape (N, 2)
        Filled.
    rotations, drops : ndarray of int64, shape (N,)
        Filled: each matrix's rotations and nonzero entries dropped (``R`` and ``D`` of the module
        doc's bound).
    a : ndarray, shape (_ROWS * LANES + 1,)
        Scratch (``lane_buffer``).
    """
    n = mats.shape[0]
    for first in range(0, n, LANES):
        for lane in range(LANES):
            i = min(first + lane, n - 1)          # a short last group repeats the last matrix
            m = mats[i]
            _load(a, lane, (m[0, 0], m[0, 1], m[0, 2], m[0, 3], m[0, 4], m[1, 1], m[1, 2], m[1, 3], m[1, 4],
                            m[2, 2], m[2, 3], m[2, 4], m[3, 3], m[3, 4], m[4, 4]))
        _jacobi(a)
        for lane in range(min(LANES, n - first)):
            out[first + lane, 0], out[first + lane, 1] = _extremes(a, lane) if _converged(a, lane) else (
                np.nan, np.nan)
            rotations[first + lane] = int(a[_ROT * LANES + lane])
            drops[first + lane] = int(a[_DROP * LANES + lane])


def lane_buffer(chunks: int = 1, sweeps: int | None = None) -> np.ndarray:
    """Scratch for ``chunks`` parallel chunks of lanes: ``_ROWS`` rows of ``LANES`` each, row-major,
    then the sweeps' cap.

    Parameters
    ----------
    chunks : int
    sweeps : int, optional
        ``_jacobi``'s cap; ``SWEEPS`` (read at the call) by default.

    Returns
    -------
    ndarray, shape (chunks, _ROWS * LANES + 1)
    """
    sweeps = SWEEPS if sweeps is None else sweeps
    if sweeps < 1:                       # no sweep: no lane's convergence is known
        raise ValueError(f"sweeps must be at least 1, got {sweeps}")
    a = np.zeros((chunks, _ROWS * LANES + 1))
    a[:, -1] = sweeps
    return a


def _run(points, geo, starts, scale, keep, st, prm, end_effector, lanes, a_out, b_out):
    """Every (run, sample) item: ``a_out``, ``b_out`` (k, m) at the runs' designs.

    ``points`` (m, 5); ``geo`` (R, 4) the runs' ``(l1, l2, l3, l6)``; ``starts`` (R + 1,) the runs'
    design ranges; ``scale`` (k, 6) each design's ``S_J`` per row q1..q6 (``keep``: actuated rows);
    ``st`` (5,) ``S_T``; ``prm`` from ``pack``; ``lanes`` (C, _ROWS * LANES) from ``lane_buffer``:
    the items in C contiguous chunks, one per parallel iteration, each filling its lanes with the
    Gram matrices of its pairs in turn and diagonalising them ``LANES`` at a time. A pair whose
    Jacobi met the cap gets ``HANDED_BACK`` in both outputs.
    """
    m = points.shape[0]
    n_items = (starts.shape[0] - 1) * m
    half, lever = prm[_HALF], prm[_LEVER]
    sts = (st[0], st[1], st[2], st[3], st[4])
    chunks = lanes.shape[0]
    for chunk in numba.prange(chunks):
        a = lanes[chunk]
        lane = 0
        for item in range(n_items * chunk // chunks, n_items * (chunk + 1) // chunks):
            r = item // m
            j = item - r * m
            x = points[j]
            fa, fp, fb = _pen_frame(x[3], x[4])
            l1, l2, l3 = geo[r, 0], geo[r, 1], geo[r, 2]
            h = lever * geo[r, 3]
            ok_a, r0, r1, r2 = _unit(x[0], x[1], x[2], fa, fp, fb, h, -half, -1.0, l1, l2, l3, prm, 0, end_effector)
            ok_b, r3, r4, r5 = _unit(x[0], x[1], x[2], fa, fp, fb, h, half, 1.0, l1, l2, l3, prm, 3, end_effector)
            if not (ok_a and ok_b):
                for d in range(starts[r], starts[r + 1]):
                    a_out[d, j] = np.nan
                    b_out[d, j] = np.nan
                continue
            finite = ((not keep[0] or _finite(r0)) and (not keep[1] or _finite(r1)) and (not keep[2] or _finite(r2))
                      and (not keep[3] or _finite(r3)) and (not keep[4] or _finite(r4))
                      and (not keep[5] or _finite(r5)))
            if not finite:             # an exact singularity: metrics.linalg.singular_values' inf
                for d in range(starts[r], starts[r + 1]):
                    a_out[d, j] = np.inf
                    b_out[d, j] = np.inf
                continue
            for d in range(starts[r], starts[r + 1]):
                g = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
                if keep[0]:
                    g = _outer_add(g, _scaled(r0, sts, scale[d, 0]))
                if keep[1]:
                    g = _outer_add(g, _scaled(r1, sts, scale[d, 1]))
                if keep[2]:
                    g = _outer_add(g, _scaled(r2, sts, scale[d, 2]))
                if keep[3]:
                    g = _outer_add(g, _scaled(r3, sts, scale[d, 3]))
                if keep[4]:
                    g = _outer_add(g, _scaled(r4, sts, scale[d, 4]))
                if keep[5]:
                    g = _outer_add(g, _scaled(r5, sts, scale[d, 5]))
                _load(a, lane, g)
                a[_D * LANES + lane], a[_J * LANES + lane] = d, j
                lane += 1
                if lane == LANES:
                    _solve(a, LANES, a_out, b_out)
                    lane = 0
        if lane:
            for rest in range(lane, LANES):    # idle lanes: zero matrices, converged at once
                _load(a, rest, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
            _solve(a, lane, a_out, b_out)


@jit()
def _solve(a, used, a_out, b_out):
    """Diagonalise the lanes and write the first ``used`` lanes' ``sigma_min``, ``sigma_max`` at their pairs."""
    _jacobi(a)
    for lane in range(used):
        lo, hi = _extremes(a, lane)
        d, j = int(a[_D * LANES + lane]), int(a[_J * LANES + lane])
        if not _converged(a, lane):
            a_out[d, j] = HANDED_BACK
            b_out[d, j] = HANDED_BACK
            continue
        a_out[d, j] = math.sqrt(max(lo, 0.0))      # a PSD matrix's eigenvalue may round below 0
        b_out[d, j] = math.sqrt(hi)


run_parallel, run_serial = twins(_run, "run")
