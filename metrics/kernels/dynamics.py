"""The motion quantities of one point, compiled, in scalars (2 x 2 and 3 x 3): masses, acceleration, speed.

The isotropic velocity needs J alone (``velocity3``, ``velocity2``: ``metrics.velocity.isotropic_velocity``'s
zonotope, its facets' normals the generalised cross products of J's columns, its offsets
``sum_u s_u |nu . J[:, u]|``, at a regular J only). The mass quantities need the kinetic form too.

The family's ``*_mass.inertia`` gives the kinetic form ``K`` in the model's ``mass_coordinates``:
the task-space inertia ``Lambda`` (task-placed models) or the joint-space ``M`` (joint-placed).
From it and ``J`` these functions follow ``metrics.quantity_nodes.inertias``, ``mass_range`` and
``metrics.dynamics.isotropic_acceleration`` formula for formula:

=========================  ===================================================  =====================
step                       formula (numpy)                                      hand back to numpy
=========================  ===================================================  =====================
mobility, task inertia     task-placed: ``Lambda = K``, ``Lambda^-1`` by the     not ``inverse_spd``'s
                           adjugate, symmetrised (``dynamics.inverse_spd``);     "sure regular" test,
                           joint-placed: ``J adj(M)/det M J^T``, symmetrised     a trace off SAFE_SCALE
                           (``mobility``), ``Lambda`` its adjugate inverse
apparent-mass range        eigenvalues ``w`` of ``Lambda^-1`` (trigonometric      a near-repeated
                           form; 2 x 2: its singular values); ``1 / w_1`` and    eigenvalue, the
                           ``1 / w_m`` (``dynamics.apparent_mass_range``)        smallest at the floor
isotropic acceleration     ``min_u t_u / |(Lambda J)[:, u]|`` (``isotropy``      as ``square3``'s
                           on ``acceleration_jacobian``)                          column norms
=========================  ===================================================  =====================

``J`` itself must be well conditioned (its Frobenius condition at most ``FAST_COND_LIMIT``, the
bound ``square3`` uses for ``J^-T``): the models' body velocities go through ``G = J^-1``. Every
other point is handed back, so singular and ill-conditioned poses get the numpy path's values,
``inf`` and labels exactly; the regular ones agree with it to a few ulps times the conditioning
(``tests/metrics/test_kernel_dynamics.py`` derives the bound).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from metrics.columns import SAFE_SUM_SQ
from metrics.linalg import FAST_COND_LIMIT, SAFE_SCALE, SURE_REGULAR

from .jit import jit

EPS = 2.220446049250313e-16
#: Value columns these quantities fill (after ``square3.COLUMNS``' six).
DYNAMIC_COLUMNS = ("apparent_mass_min", "apparent_mass_max", "isotropic_acceleration", "isotropic_velocity")
_FIRST = 6
_SCALE_LO, _SCALE_HI = SAFE_SCALE
_SUM_LO, _SUM_HI = SAFE_SUM_SQ
_FRO_LO, _FRO_HI = SAFE_SCALE[0] ** 2, SAFE_SCALE[1] ** 2
_THIRD_TURN = 2.0 * math.pi / 3.0


@jit()
def _safe(value):
    return value > _SCALE_LO and value < _SCALE_HI


@jit()
def regular3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """Whether J's Frobenius condition ``|J|_F |cof J|_F / |det J|`` is at most ``FAST_COND_LIMIT``."""
    fro = a00 * a00 + a01 * a01 + a02 * a02 + a10 * a10 + a11 * a11 + a12 * a12 + a20 * a20 + a21 * a21 + a22 * a22
    if not (fro > _FRO_LO and fro < _FRO_HI):
        return False
    f00, f01, f02 = a11 * a22 - a21 * a12, a12 * a20 - a22 * a10, a10 * a21 - a20 * a11
    f10, f11, f12 = a21 * a02 - a01 * a22, a22 * a00 - a02 * a20, a20 * a01 - a00 * a21
    f20, f21, f22 = a01 * a12 - a11 * a02, a02 * a10 - a12 * a00, a00 * a11 - a10 * a01
    cof = f00 * f00 + f01 * f01 + f02 * f02 + f10 * f10 + f11 * f11 + f12 * f12 + f20 * f20 + f21 * f21 + f22 * f22
    det = a00 * f00 + a10 * f10 + a20 * f20
    return math.sqrt(fro * cof) / abs(det) <= FAST_COND_LIMIT


@jit()
def _inverse_sym3(s00, s01, s02, s11, s12, s22):
    """``(ok, inverse's upper triangle)`` of a symmetric matrix by its adjugate (``dynamics._inverse_closed``).

    ``ok`` is ``inverse_spd``'s "sure regular" test, ``det > SURE_REGULAR m eps tr^m`` with the trace
    and trace / m inside ``SAFE_SCALE``: where it fails, numpy looks at eigenvalues (the caller hands
    the point back).
    """
    c00, c01, c02 = s11 * s22 - s12 * s12, s12 * s02 - s22 * s01, s01 * s12 - s02 * s11
    c11, c12, c22 = s22 * s00 - s02 * s02, s02 * s01 - s00 * s12, s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    tr = s00 + s11 + s22
    ok = _safe(tr) and _safe(tr / 3.0) and det > SURE_REGULAR * 3.0 * EPS * tr * tr * tr
    return ok, c00 / det, c01 / det, c02 / det, c11 / det, c12 / det, c22 / det


#: Jacobi sweeps after which ``_jacobi_sym3`` gives up (hands the matrix back); 3 x 3 converges
#: quadratically, in 3-5 sweeps for any matrix in double precision.
_JACOBI_SWEEPS = 12


@jit()
def _rotated(app, aqq, apq, arp, arq):
    """One Jacobi rotation annihilating ``a_pq`` (Rutishauser's form): ``(a_pp, a_qq, a_rp, a_rq)`` after it."""
    theta = (aqq - app) / (2.0 * apq)
    if abs(theta) > 1e150:          # theta^2 would overflow: t = 1 / (2 theta) to working precision
        t = 0.5 / theta
    else:
        t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1.0))
    c = 1.0 / math.sqrt(t * t + 1.0)
    sn = t * c
    tau = sn / (1.0 + c)
    return app - t * apq, aqq + t * apq, arp - sn * (arq + tau * arp), arq + sn * (arp - tau * arq)


@jit()
def _jacobi_sym3(s00, s01, s02, s11, s12, s22):
    """``(hard, w1, w2, w3)``, descending, of a symmetric positive definite 3 x 3 matrix by cyclic Jacobi.

    For the near-repeated eigenvalues the trigonometric form cannot resolve. Each rotation is
    backward stable, so the eigenvalues carry an absolute error of a few ``eps`` times the
    largest, as LAPACK's ``eigvalsh`` (numpy's choice there); an off-diagonal entry is dropped
    once it is below ``eps sqrt(a_pp a_qq)``, which moves no eigenvalue of a positive definite
    matrix by more than ``eps`` relative to it (Demmel and Veselic). ``hard`` if a diagonal entry
    is not positive (not positive definite) or the sweeps do not converge.
    """
    a00, a11, a22, a01, a02, a12 = s00, s11, s22, s01, s02, s12
    for _ in range(_JACOBI_SWEEPS):
        if not (a00 > 0.0 and a11 > 0.0 and a22 > 0.0):
            return True, 0.0, 0.0, 0.0
        if abs(a01) <= EPS * math.sqrt(a00 * a11):
            a01 = 0.0
        if abs(a02) <= EPS * math.sqrt(a00 * a22):
            a02 = 0.0
        if abs(a12) <= EPS * math.sqrt(a11 * a22):
            a12 = 0.0
        if a01 == 0.0 and a02 == 0.0 and a12 == 0.0:
            lo, hi = min(a00, a11), max(a00, a11)          # sorted, descending
            return False, max(hi, a22), max(lo, min(hi, a22)), min(lo, a22)
        if a01 != 0.0:              # (p, q, r) = (0, 1, 2)
            a00, a11, a02, a12 = _rotated(a00, a11, a01, a02, a12)
            a01 = 0.0
        if a02 != 0.0:              # (0, 2, 1)
            a00, a22, a01, a12 = _rotated(a00, a22, a02, a01, a12)
            a02 = 0.0
        if a12 != 0.0:              # (1, 2, 0)
            a11, a22, a01, a02 = _rotated(a11, a22, a12, a01, a02)
            a12 = 0.0
    return True, 0.0, 0.0, 0.0


@jit()
def _eigenvalues_sym3(s00, s01, s02, s11, s12, s22):
    """``(hard, w1, w2, w3)``, descending: ``linalg.symmetric_eigenvalues_3x3``'s trigonometric form.

    numpy scales each matrix by a power of two first; within ``SAFE_SCALE`` that scaling changes
    no bit of the result, so it is left out and a matrix outside is handed back (``hard``). A
    near-repeated eigenvalue (``|r| > 1 - 1e-3``), where ``arccos`` loses digits and numpy calls
    LAPACK, takes Jacobi's method (``_jacobi_sym3``), as accurate as LAPACK's.
    """
    big = max(max(max(abs(s00), abs(s01)), max(abs(s02), abs(s11))), max(abs(s12), abs(s22)))
    if not _safe(big):
        return True, 0.0, 0.0, 0.0
    mean = (s00 + s11 + s22) / 3.0
    d0, d1, d2 = s00 - mean, s11 - mean, s22 - mean
    p = math.sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (s01 * s01 + s02 * s02 + s12 * s12)) / 6.0)
    det_shift = d0 * (d1 * d2 - s12 * s12) - s01 * (s01 * d2 - s12 * s02) + s02 * (s01 * s12 - d1 * s02)
    r = det_shift / (2.0 * p * p * p) if p > 0.0 else 0.0
    if abs(r) > 1.0 - 1e-3:
        return _jacobi_sym3(s00, s01, s02, s11, s12, s22)
    phi = math.acos(min(max(r, -1.0), 1.0)) / 3.0
    lam1 = mean + 2.0 * p * math.cos(phi)
    lam3 = mean + 2.0 * p * math.cos(phi + _THIRD_TURN)
    return False, lam1, 3.0 * mean - lam1 - lam3, lam3


@jit()
def _column_radius(c0, c1, c2, t0, t1, t2, size):
    """``(hard, min_u t_u / sqrt(c_u))`` from column sums of squares ``c_u`` (``isotropy.isotropic_force``).

    Hard (numpy's scaled norms decide) where a sum leaves ``SAFE_SUM_SQ`` or a column is negligible
    beside the largest (``square3``'s conditions). ``size``: 2 or 3 (``c2`` unused for 2).
    """
    if not (c0 > _SUM_LO and c0 < _SUM_HI and c1 > _SUM_LO and c1 < _SUM_HI):
        return True, 0.0
    n0, n1 = math.sqrt(c0), math.sqrt(c1)
    top = max(n0, n1)
    n2 = 0.0
    if size == 3:
        if not (c2 > _SUM_LO and c2 < _SUM_HI):
            return True, 0.0
        n2 = math.sqrt(c2)
        top = max(top, n2)
    level = (size * EPS) * top
    if n0 <= level or n1 <= level or (size == 3 and n2 <= level):
        return True, 0.0
    radius = min(t0 / n0, t1 / n1)
    if size == 3:
        radius = min(radius, t2 / n2)
    return False, radius


@jit()
def dynamics3(k00, k01, k02, k11, k12, k22, a00, a01, a02, a10, a11, a12, a20, a21, a22, joint_placed, t, out, i,
              want_mass, want_acceleration):
    """Point ``i``'s apparent-mass range and isotropic acceleration into ``out[6:9, i]``; True to hand it back.

    Parameters
    ----------
    k00, k01, k02, k11, k12, k22 : float
        Upper triangle of the kinetic form (``Lambda``, kg, or ``M``, kg m^2, per ``joint_placed``).
    a00 ... a22 : float
        ``J[r, c]``.
    joint_placed : bool
        ``K`` is ``M(q)`` (``mass_coordinates = "joint"``), else ``Lambda``.
    t : ndarray, shape (3,)
        Joint torque limits.
    out : ndarray, shape (9, k)
        The kernel's value columns.
    i : int
        The point.
    want_mass, want_acceleration : bool
        Which of the two to compute.
    """
    if not regular3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
        return True
    if joint_placed:
        ok, m00, m01, m02, m11, m12, m22 = _inverse_sym3(k00, k01, k02, k11, k12, k22)
        if not ok:
            return True
        # (J M^-1) J^T, then symmetrised (dynamics.mobility).
        b00 = a00 * m00 + a01 * m01 + a02 * m02
        b01 = a00 * m01 + a01 * m11 + a02 * m12
        b02 = a00 * m02 + a01 * m12 + a02 * m22
        b10 = a10 * m00 + a11 * m01 + a12 * m02
        b11 = a10 * m01 + a11 * m11 + a12 * m12
        b12 = a10 * m02 + a11 * m12 + a12 * m22
        b20 = a20 * m00 + a21 * m01 + a22 * m02
        b21 = a20 * m01 + a21 * m11 + a22 * m12
        b22 = a20 * m02 + a21 * m12 + a22 * m22
        w00 = b00 * a00 + b01 * a01 + b02 * a02
        w11 = b10 * a10 + b11 * a11 + b12 * a12
        w22 = b20 * a20 + b21 * a21 + b22 * a22
        w01 = 0.5 * ((b00 * a10 + b01 * a11 + b02 * a12) + (b10 * a00 + b11 * a01 + b12 * a02))
        w02 = 0.5 * ((b00 * a20 + b01 * a21 + b02 * a22) + (b20 * a00 + b21 * a01 + b22 * a02))
        w12 = 0.5 * ((b10 * a20 + b11 * a21 + b12 * a22) + (b20 * a10 + b21 * a11 + b22 * a12))
        ok, l00, l01, l02, l11, l12, l22 = _inverse_sym3(w00, w01, w02, w11, w12, w22)
    else:
        l00, l01, l02, l11, l12, l22 = k00, k01, k02, k11, k12, k22
        ok, w00, w01, w02, w11, w12, w22 = _inverse_sym3(l00, l01, l02, l11, l12, l22)
    if not ok:
        return True
    if want_mass:
        hard, e1, e2, e3 = _eigenvalues_sym3(w00, w01, w02, w11, w12, w22)
        if hard or not (e3 > 3.0 * EPS * max(abs(e1), max(abs(e2), abs(e3)))):
            return True
        out[_FIRST, i] = 1.0 / e1
        out[_FIRST + 1, i] = 1.0 / e3
    if want_acceleration:
        # Columns of Lambda J (dynamics.acceleration_jacobian), their sums of squares.
        c0 = l00 * a00 + l01 * a10 + l02 * a20
        c1 = l01 * a00 + l11 * a10 + l12 * a20
        c2 = l02 * a00 + l12 * a10 + l22 * a20
        s0 = c0 * c0 + c1 * c1 + c2 * c2
        c0 = l00 * a01 + l01 * a11 + l02 * a21
        c1 = l01 * a01 + l11 * a11 + l12 * a21
        c2 = l02 * a01 + l12 * a11 + l22 * a21
        s1 = c0 * c0 + c1 * c1 + c2 * c2
        c0 = l00 * a02 + l01 * a12 + l02 * a22
        c1 = l01 * a02 + l11 * a12 + l12 * a22
        c2 = l02 * a02 + l12 * a12 + l22 * a22
        s2 = c0 * c0 + c1 * c1 + c2 * c2
        hard, radius = _column_radius(s0, s1, s2, t[0], t[1], t[2], 3)
        if hard:
            return True
        out[_FIRST + 2, i] = radius
    return False


@jit()
def dynamics2(k00, k01, k11, a00, a01, a10, a11, t, out, i, want_mass, want_acceleration):
    """``dynamics3`` for a task-placed 2 x 2 model (the five-bar): ``K = Lambda``.

    The eigenvalues of ``Lambda^-1`` are its singular values' closed form (``linalg._sv_2x2``), handed
    back off ``SAFE_SCALE`` or where the condition exceeds ``FAST_COND_LIMIT`` (numpy's own switch
    to LAPACK).
    """
    fro = a00 * a00 + a01 * a01 + a10 * a10 + a11 * a11
    det_j = a00 * a11 - a10 * a01
    # 2 x 2: |cof J|_F = |J|_F, so the Frobenius condition is |J|_F^2 / |det J|.
    if not (fro > _FRO_LO and fro < _FRO_HI and fro / abs(det_j) <= FAST_COND_LIMIT):
        return True
    det = k00 * k11 - k01 * k01
    tr = k00 + k11
    if not (_safe(tr) and _safe(tr / 2.0) and det > SURE_REGULAR * 2.0 * EPS * tr * tr):
        return True
    w00, w01, w11 = k11 / det, -k01 / det, k00 / det
    if want_mass:
        big = 0.5 * (math.hypot(w00 + w11, w01 - w01) + math.hypot(w00 - w11, w01 + w01))
        if not _safe(big):
            return True
        small = min(abs(w00 * w11 - w01 * w01) / big, big)
        if not (small * FAST_COND_LIMIT >= big and small > 2.0 * EPS * big):
            return True
        out[_FIRST, i] = 1.0 / big
        out[_FIRST + 1, i] = 1.0 / small
    if want_acceleration:
        c0 = k00 * a00 + k01 * a10
        c1 = k01 * a00 + k11 * a10
        s0 = c0 * c0 + c1 * c1
        c0 = k00 * a01 + k01 * a11
        c1 = k01 * a01 + k11 * a11
        s1 = c0 * c0 + c1 * c1
        hard, radius = _column_radius(s0, s1, 0.0, t[0], t[1], 0.0, 2)
        if hard:
            return True
        out[_FIRST + 2, i] = radius
    return False


@jit()
def _facet3(u0, u1, u2, v0, v1, v2, a00, a01, a02, a10, a11, a12, a20, a21, a22, s):
    """Offset ``sum_k s_k |nu . J[:, k]|`` of the facet whose unit normal ``nu`` is ``u x v`` normalised."""
    n0, n1, n2 = u1 * v2 - v1 * u2, -(u0 * v2 - v0 * u2), u0 * v1 - v0 * u1
    length = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    n0, n1, n2 = n0 / length, n1 / length, n2 / length
    return (s[0] * abs(n0 * a00 + n1 * a10 + n2 * a20) + s[1] * abs(n0 * a01 + n1 * a11 + n2 * a21)
            + s[2] * abs(n0 * a02 + n1 * a12 + n2 * a22))


@jit()
def velocity3(a00, a01, a02, a10, a11, a12, a20, a21, a22, s, out, i):
    """Point ``i``'s isotropic velocity into ``out[9, i]``; True to hand it back (J not regular).

    The smallest offset of the zonotope ``J [-s, s]^3``: its three facet pairs, normal to two of
    J's columns each (``zonotopes.zonotope``'s subsets (0, 1), (0, 2), (1, 2)).
    """
    if not regular3(a00, a01, a02, a10, a11, a12, a20, a21, a22):
        return True
    h01 = _facet3(a00, a10, a20, a01, a11, a21, a00, a01, a02, a10, a11, a12, a20, a21, a22, s)
    h02 = _facet3(a00, a10, a20, a02, a12, a22, a00, a01, a02, a10, a11, a12, a20, a21, a22, s)
    h12 = _facet3(a01, a11, a21, a02, a12, a22, a00, a01, a02, a10, a11, a12, a20, a21, a22, s)
    out[_FIRST + 3, i] = min(min(h01, h02), h12)
    return False


@jit()
def velocity2(a00, a01, a10, a11, s, out, i):
    """``velocity3`` for a 2 x 2 J: the facets normal to each column, ``nu = (a_1u, -a_0u)`` normalised."""
    fro = a00 * a00 + a01 * a01 + a10 * a10 + a11 * a11
    if not (fro > _FRO_LO and fro < _FRO_HI and fro / abs(a00 * a11 - a10 * a01) <= FAST_COND_LIMIT):
        return True
    best = math.inf
    for u in range(2):
        n0, n1 = (a10, -a00) if u == 0 else (a11, -a01)
        length = math.sqrt(n0 * n0 + n1 * n1)
        n0, n1 = n0 / length, n1 / length
        best = min(best, s[0] * abs(n0 * a00 + n1 * a10) + s[1] * abs(n0 * a01 + n1 * a11))
    out[_FIRST + 3, i] = best
    return False


#: Floats per body in a family's ``pack_mass`` array: mass, centre (3), inertia tensor (6).
BODY_FLOATS = 10


def pack_bodies(mechanism, names: tuple[str, ...], out: np.ndarray, first: int) -> None:
    """Write the model's bodies into ``out`` from ``first``, ``BODY_FLOATS`` each, in the order ``names``.

    Per body: mass (kg), centre of mass in the body frame (3, m), inertia tensor about it in body
    axes ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m^2, ``Body.inertia``): what each family's
    ``*_mass.pack_mass`` lays out after its own parameters.

    Parameters
    ----------
    mechanism : Mechanism
        With a mass model (``bodies()`` raises otherwise).
    names : tuple of str
        The bodies the family's ``inertia`` reads, in its order.
    out : ndarray, shape (>= first + BODY_FLOATS len(names),)
        The packed array, written in place.
    first : int
        Where the first body starts.

    Raises
    ------
    ValueError
        When the model's bodies are not ``names`` in this order.
    """
    bodies = mechanism.bodies()
    got = tuple(b.name for b in bodies)
    if got != names:
        raise ValueError(f"{type(mechanism).__name__}: the compiled kinetic form needs the bodies {names} in this "
                         f"order, got {got}")
    for b, body in enumerate(bodies):
        at = first + BODY_FLOATS * b
        out[at] = body.mass
        out[at + 1:at + 4] = body.com
        out[at + 4:at + BODY_FLOATS] = body.inertia


def inertia_points_of(inertia, x, q, jac, mp):
    """A family's compiled ``inertia`` at k poses, as full symmetric matrices (k, m, m): for tests and benchmarks.

    Parameters
    ----------
    inertia : numba Dispatcher
        A ``*_mass.inertia``: ``(x..., q..., J entries..., mp) -> upper triangle``.
    x : ndarray, shape (k, m)
        Task points, m.
    q : ndarray, shape (k, m)
        Their joints.
    jac : ndarray, shape (k, m, m)
        Their Jacobians.
    mp : ndarray
        The family's ``pack_mass``.

    Returns
    -------
    ndarray, shape (k, m, m)
    """
    x, q, jac = (np.ascontiguousarray(a, dtype=np.float64) for a in (x, q, jac))
    return (_points3 if x.shape[1] == 3 else _points2)(inertia, x, q, jac, np.ascontiguousarray(mp, np.float64))


# Not cached: numba keeps no cache for a function that takes another compiled function as an argument.
@numba.njit(nogil=True, error_model="numpy")
def _points3(inertia, x, q, jac, mp):
    out = np.empty((x.shape[0], 3, 3))
    for i in range(x.shape[0]):
        j = jac[i]
        f = inertia(x[i, 0], x[i, 1], x[i, 2], q[i, 0], q[i, 1], q[i, 2],
                    j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2], j[2, 0], j[2, 1], j[2, 2], mp)
        out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = f[0], f[1], f[2]
        out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = f[1], f[3], f[4]
        out[i, 2, 0], out[i, 2, 1], out[i, 2, 2] = f[2], f[4], f[5]
    return out


@numba.njit(nogil=True, error_model="numpy")
def _points2(inertia, x, q, jac, mp):
    out = np.empty((x.shape[0], 2, 2))
    for i in range(x.shape[0]):
        f = inertia(x[i, 0], x[i, 1], q[i, 0], q[i, 1], jac[i, 0, 0], jac[i, 0, 1], jac[i, 1, 0], jac[i, 1, 1], mp)
        out[i, 0, 0], out[i, 0, 1], out[i, 1, 0], out[i, 1, 1] = f[0], f[1], f[1], f[2]
    return out
