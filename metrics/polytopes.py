"""Force polytopes: reference forces, vertices, isotropic and anisotropic force, force clamp.

For a square Jacobian the forces the device holds with ``|tau_u| <= t_u`` form the
parallelepiped ``P = {f : |J[:, u] . f| <= t_u}`` (paper 000 sec. 2). Its vertices are
``J^-T (+-t_1, ..., +-t_n)``; the columns of ``R = J^-T diag(t)`` are the paper's reference
forces (eq. 3-6).

=========================  ============================================  ======================
quantity                   how we compute it                             paper 000
=========================  ============================================  ======================
isotropic force            min_u t_u / |J[:, u]|: the distance from 0    eq. 7-8 (same value,
                           to facet u, no inverse, finite at             no cross products of
                           singularities                                 reference forces)
bottleneck actuator        argmin of the same                            --
anisotropic force          max vertex norm, vertices from J^-T           eq. 6
force clamp                F_d scaled down to the isotropic radius       eq. 9
=========================  ============================================  ======================

With redundant actuation (``f = A tau`` with ``A`` of shape (m, n), n > m) the force set
is the zonotope ``A [-t, t]^n``: ``metrics.zonotopes`` handles it.

Asymmetric limits and a torque bias (``torque_min=``, default ``-torque_limits``;
``torque_bias=``, default 0; as in pycapacity's ``force_polytope(J, t_max, t_min, t_bias)``
the bias is torque the joints already spend) leave the usable range
``lo = torque_min - b <= tau <= hi = torque_limits - b`` (``torque_range``). The force set
is then a shifted parallelepiped ``{f : lo <= J^T f <= hi}`` or zonotope ``A [lo, hi]``:

=========================  ============================================  ======================
quantity                   how we compute it (lo, hi)                    symmetric case
=========================  ============================================  ======================
facet distances            min(hi_u, -lo_u) / |J[:, u]|, signed:         t_u / |J[:, u]|
                           negative where 0 is outside slab u
isotropic force            max(0, min_u of the same): distance from 0    min_u t_u / |J[:, u]|
                           to the nearest facet, 0 outside the set
bottleneck actuator        argmin of the same, clipped at 0 (every       same
                           actuator that excludes 0 ties)
reference forces           half-edges J^-T diag((hi - lo) / 2) about     J^-T diag(t)
                           the centre J^-T (hi + lo) / 2
                           (``polytope_centre``)
vertices                   J^-T v, v_u = hi_u (s_u = +1) or lo_u         J^-T diag(t) s
anisotropic force          max vertex norm (all 2^n, no +- symmetry)     max over half
zonotope facets            +-nu_k, offsets H_k +- nu_k . A (hi + lo)/2,  H_k = sum_u t_u
                           H_k = sum_u (hi - lo)_u / 2 |A_u . nu_k|      |A_u . nu_k|
=========================  ============================================  ======================

Where neither ``torque_min`` nor ``torque_bias`` is given, or the range comes out centred
(``lo == -hi`` everywhere), the symmetric code runs unchanged (bit-identical numbers).

Over 600 lines for a stated reason: about 550 of them are docstrings (numpydoc sections and
doctests); the code is about 270 lines, the symmetric and asymmetric cases of one force set,
which share their facet and vertex helpers. The redundant case is ``metrics.zonotopes``.
"""
from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.base import FloatArray

from .ellipsoids import actuator_limits
from .linalg import as_jacobian, components, gram, inverse_transpose, pow2_exponents

#: Bottleneck codes besides an actuator index (``-1`` is an infeasible point, see ``evaluate``):
#: two or more actuators' facets are equally near the origin within rounding (a tie), or the
#: actuation is redundant and no single actuator caps the isotropic force (shared).
BOTTLENECK_INFEASIBLE = -1
BOTTLENECK_TIE = -2
BOTTLENECK_SHARED = -3


def sign_patterns(n: int, *, half: bool = False) -> FloatArray:
    """All ``2^n`` sign vectors (rows, shape (2^n, n)); ``half`` keeps one of each +-pair.

    Parameters
    ----------
    n : int
        Number of actuators.
    half : bool
        Keep only the rows with a positive first entry (``2^(n-1)`` rows).

    Returns
    -------
    ndarray, shape (2^n, n), or (2^(n-1), n) with ``half``
        Entries +-1.0, in ``itertools.product((1.0, -1.0), repeat=n)`` order.

    Examples
    --------
    >>> sign_patterns(2).tolist()
    [[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]]
    >>> sign_patterns(3, half=True).shape
    (4, 3)
    """
    rows = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    return rows[rows[:, 0] > 0] if half else rows


#: Sums of squares strictly between these are formed as given: no square overflowed, and the
#: squares that underflowed (below 2^-1022 each) are below 2^-120 of the sum.
_SAFE_SUM_SQ = (2.0 ** -900, 2.0 ** 1000)


def _sum_squares(a: FloatArray) -> FloatArray:
    """``sum_k a[k]^2`` over the first axis of entry arrays (m, ...)."""
    acc = a[0] * a[0]
    for k in range(1, a.shape[0]):
        acc += a[k] * a[k]
    return acc


def column_norms(jac: ArrayLike) -> FloatArray:
    """Euclidean norm of each Jacobian column, shape (..., n); ``inf`` for a non-finite column.

    The sum of squares is formed as given where it cannot have over- or underflowed (nearly
    always); other columns are scaled by a power of two first (exact) and scaled back, so
    ``column_norms(c * J) = |c| column_norms(J)`` for any representable result.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians.

    Returns
    -------
    ndarray, shape (..., n)
        In the unit of ``J`` (m/rad).

    Examples
    --------
    >>> column_norms([[3.0, 0.0], [4.0, 1.0]]).tolist()
    [5.0, 1.0]
    """
    a = components(as_jacobian(jac))
    with np.errstate(over="ignore", invalid="ignore"):
        acc = _sum_squares(a)
    lo, hi = _SAFE_SUM_SQ
    with np.errstate(invalid="ignore"):
        norms = np.sqrt(acc)
        redo = ~((acc > lo) & (acc < hi))
    if np.any(redo):
        cols = a[:, redo]                              # (m, k): the columns to redo
        e = pow2_exponents(cols, axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            norms[redo] = np.ldexp(np.sqrt(_sum_squares(np.ldexp(cols, -e))), e)
    norms = np.moveaxis(norms, 0, -1)
    return np.where(np.isnan(norms), np.inf, norms)


def negligible_columns(norms: ArrayLike) -> np.ndarray:
    """Columns (..., n) whose norm is at rounding level, ``<= n eps max_v |J[:, v]|``: zero to rounding.

    A Jacobian computed in floating point carries absolute errors of order eps times its
    scale in every entry; a column no larger than ``n`` such errors cannot be told from an
    exactly zero one (the actuator moves nothing). The largest column norm is within
    ``sqrt(n)`` of ``sigma_max``, so such a column also makes ``sigma_min <= n eps sigma_max``,
    the level at which ``condition_number`` and ``inverse_transpose`` call J singular.
    Where a column is unbounded (``inf``) nothing is negligible.

    Parameters
    ----------
    norms : array_like, shape (..., n)
        Column norms (``column_norms``).

    Returns
    -------
    ndarray of bool, shape (..., n)

    Examples
    --------
    >>> negligible_columns([1.0, 1e-17, 0.5]).tolist()
    [False, True, False]
    """
    norms = np.asarray(norms, float)
    n = norms.shape[-1]
    scale = norms[..., 0]
    for k in range(1, n):          # elementwise over columns: faster than a reduction along a short axis
        scale = np.maximum(scale, norms[..., k])
    with np.errstate(invalid="ignore", over="ignore"):
        level = (n * np.finfo(float).eps) * scale[..., None]
        negligible = norms <= level
    if negligible.any():
        negligible &= np.isfinite(level)
    return negligible


def _finite_torques(name: str, values: ArrayLike, n: int) -> FloatArray:
    """Finite per-actuator torques broadcastable to ``(..., n)`` (any sign), or raise naming ``name``."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}) to match the Jacobian's {n} columns, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def torque_range(torque_limits: ArrayLike, *, n: int, torque_min: ArrayLike | None = None,
                 torque_bias: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
    """Usable joint-torque range ``[torque_min - torque_bias, torque_limits - torque_bias]``.

    As in pycapacity's ``force_polytope(J, t_max, t_min, t_bias)``: the bias is torque the
    joints already spend (a preload, gravity compensation), so the force set is
    ``{f : lo <= J^T f <= hi}``.

    Parameters
    ----------
    torque_limits : array_like, shape (..., n)
        Upper joint torque limits ``t_max``, N m. Positive when ``torque_min`` is not given.
    n : int
        Number of actuators (columns of J).
    torque_min : array_like, shape (..., n), optional
        Lower limits ``t_min < t_max``, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque already spent ``b``, N m; default 0.

    Returns
    -------
    lo, hi : ndarray, shape (..., n)
        ``t_min - b`` and ``t_max - b``, broadcast to one shape, N m.

    Raises
    ------
    ValueError
        Naming the argument, for a wrong shape, a non-finite value, or ``t_min >= t_max``.

    Examples
    --------
    >>> lo, hi = torque_range([2.0, 3.0], n=2, torque_min=[-1.0, -3.0], torque_bias=[0.5, 0.0])
    >>> lo.tolist(), hi.tolist()
    ([-1.5, -3.0], [1.5, 3.0])
    """
    if torque_min is None:
        hi = actuator_limits("torque_limits", torque_limits, n)
        lo = -hi
    else:
        hi = _finite_torques("torque_limits", torque_limits, n)
        lo = _finite_torques("torque_min", torque_min, n)
        if not np.all(lo < hi):
            raise ValueError(f"torque_min must be below torque_limits for every actuator, got torque_min = "
                             f"{lo.tolist()} and torque_limits = {hi.tolist()}")
    if torque_bias is not None:
        b = _finite_torques("torque_bias", torque_bias, n)
        with np.errstate(over="ignore"):
            lo, hi = lo - b, hi - b
    lo, hi = np.broadcast_arrays(lo, hi)
    return lo, hi


def asymmetric_range(jac: ArrayLike | None, norms: ArrayLike | None, torque_limits: ArrayLike,
                torque_min: ArrayLike | None, torque_bias: ArrayLike | None):
    """``None`` for the symmetric fast path, an array ``t`` for a centred range, else ``(lo, hi)``.

    Shared by the parallelepiped here and the zonotope (``metrics.zonotopes``); the arguments are
    those of ``facet_distances`` (``jac`` or its column ``norms``, shape (..., n)).

    A range that comes out centred (``lo == -hi`` everywhere) takes the fast path with
    ``t = hi``: its numbers are the symmetric ones, bit for bit.
    """
    if torque_min is None and torque_bias is None:
        return None
    n = (np.shape(norms) if norms is not None else as_jacobian(jac).shape)[-1]
    lo, hi = torque_range(torque_limits, n=n, torque_min=torque_min, torque_bias=torque_bias)
    return hi if np.array_equal(lo, -hi) else (lo, hi)


def facet_distances(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                    norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Distance ``t_u / |J[:, u]|`` from the origin to each facet pair of P, shape (..., n), in N.

    A zero column (the actuator's joint cannot move the end-effector), or one at rounding
    level relative to J (``negligible_columns``), gives ``inf``: that actuator limits no
    direction. An unbounded column (a direct singularity) gives 0.

    With ``torque_min`` or ``torque_bias`` (usable range ``[lo, hi]``, ``torque_range``) the
    slab of actuator u is ``lo_u <= J[:, u] . f <= hi_u`` and its entry is the signed distance
    ``min(hi_u, -lo_u) / |J[:, u]|`` to the nearer of its two facets: negative where the
    origin is outside the slab (0 is not in ``[lo_u, hi_u]``). A negligible column gives
    ``inf`` if 0 is in the range, else ``-inf`` (no force gives that actuator a usable torque).

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``norms``.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m.
    norms : array_like, shape (..., n), optional
        ``column_norms(jac)`` already computed.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., n)
        N.

    Examples
    --------
    >>> facet_distances([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    [0.2, 2.0]
    >>> facet_distances(np.eye(2), torque_limits=[1.0, 2.0], torque_min=[-3.0, 0.5]).tolist()
    [1.0, -0.5]
    """
    norms = column_norms(jac) if norms is None else np.asarray(norms, float)
    asym = asymmetric_range(jac, norms, torque_limits, torque_min, torque_bias)
    if isinstance(asym, tuple):
        lo, hi = asym
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            dist = np.minimum(hi, -lo) / norms
        negligible = negligible_columns(norms)
        if negligible.any():
            inside = (lo <= 0) & (hi >= 0)
            dist = np.where(negligible, np.where(inside, np.inf, -np.inf), dist)
        return dist
    if asym is not None:
        torque_limits = asym
    t = actuator_limits("torque_limits", torque_limits, norms.shape[-1])
    with np.errstate(divide="ignore", over="ignore"):
        dist = t / norms
    negligible = negligible_columns(norms)
    return np.where(negligible, np.inf, dist) if negligible.any() else dist


def isotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                    norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Maximum isotropic force (paper 000 eq. 8): radius of the largest ball about 0 in P, shape (...).

    ``min_u t_u / |J[:, u]|``, equal to eq. 8's ``min_u |R_u . N_u| / |N_u|`` but with no
    inverse: finite at singularities, zero where J is unbounded (a direct singularity).

    With ``torque_min`` or ``torque_bias`` the set ``{f : lo <= J^T f <= hi}`` is a shifted
    parallelepiped (any m x n J: an intersection of slabs) and this is the distance from the
    origin to its nearest facet, ``max(0, min_u min(hi_u, -lo_u) / |J[:, u]|)``: 0 where the
    origin is outside the set.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``norms``.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m.
    norms : array_like, shape (..., n), optional
        ``column_norms(jac)`` already computed.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend (preload, gravity compensation), N m; default 0.

    Returns
    -------
    ndarray, shape (...)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 7-8.

    Examples
    --------
    >>> isotropic_force([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    0.2
    >>> isotropic_force(np.tile(np.eye(3), (5, 1, 1)), torque_limits=[1.0, 2.0, 3.0]).tolist()
    [1.0, 1.0, 1.0, 1.0, 1.0]
    >>> isotropic_force(np.eye(2), torque_limits=[1.0, 2.0], torque_bias=[0.25, 0.0]).tolist()
    0.75
    >>> isotropic_force(np.eye(2), torque_limits=[1.0, 2.0], torque_bias=[1.5, 0.0]).tolist()
    0.0
    """
    dist = facet_distances(jac, torque_limits=torque_limits, norms=norms, torque_min=torque_min,
                           torque_bias=torque_bias)
    radius = np.min(dist, axis=-1)
    if (torque_min is not None or torque_bias is not None) and np.any(radius <= 0):
        radius = np.where(radius > 0, radius, 0.0)        # outside the set (or -0.0): 0
    return radius


def tie_tolerance(n: int) -> float:
    """Relative gap ``(n + 4) eps`` within which two facet distances of an (n, n) J are a tie.

    Each facet distance ``t_u / |J[:, u]|`` is the quotient of a square root of a sum of ``n``
    squares: its relative rounding error is at most ``(n/2 + 1) u + u/2 + u <= (n/4 + 1) eps``
    (``u = eps/2``: ``n`` products and sums, the root halving theirs, the quotient), so two
    equal distances can come out ``(n/2 + 2) eps`` apart. The factor 2 allows as much again
    for the rounding in J's entries, which a mechanism computes in a few operations each.
    The Inverse3's p1 and p2 columns, equal in exact arithmetic over the whole slice, come
    out up to 2 eps apart, and no pair of its facets lies between 4 eps and 64 eps apart.

    Parameters
    ----------
    n : int
        Number of actuators (columns of J).

    Returns
    -------
    float
        Relative gap, dimensionless.

    Examples
    --------
    >>> tie_tolerance(3) == 7 * float(np.finfo(float).eps)
    True
    """
    return (n + 4) * float(np.finfo(float).eps)


def bottleneck_actuator(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                        norms: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                        torque_bias: ArrayLike | None = None) -> np.ndarray:
    """Index of the actuator whose facet is nearest the origin (limits isotropy), shape (...), int.

    ``BOTTLENECK_TIE`` where a second facet is as near within rounding
    (``d_v <= d_min (1 + tie_tolerance(n))``): actuators that limit equally, which rounding
    must not pick between. That includes every facet at infinity (``J = 0``) or at 0.

    With ``torque_min`` or ``torque_bias``: the actuator of the nearest facet of the shifted
    set (``facet_distances``), with negative distances taken as 0, so where the origin is
    outside the set the one actuator whose range excludes 0, or a tie of several.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), optional
        Jacobians; not needed with ``norms``.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m.
    norms : array_like, shape (..., n), optional
        ``column_norms(jac)`` already computed.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray of int, shape (...)
        Actuator index, or ``BOTTLENECK_TIE``.

    Examples
    --------
    >>> bottleneck_actuator([[3.0, 0.0], [4.0, 1.0]], torque_limits=[1.0, 2.0]).tolist()
    0
    >>> int(bottleneck_actuator(np.eye(2), torque_limits=[1.0, 1.0])) == BOTTLENECK_TIE
    True
    """
    dist = facet_distances(jac, torque_limits=torque_limits, norms=norms, torque_min=torque_min,
                           torque_bias=torque_bias)
    if torque_min is not None or torque_bias is not None:
        dist = np.where(dist > 0, dist, 0.0)
    return bottleneck_of_distances(dist)


def bottleneck_of_distances(dist: ArrayLike) -> np.ndarray:
    """``bottleneck_actuator`` from facet distances (..., n) already computed (e.g. of a force slice).

    Parameters
    ----------
    dist : array_like, shape (..., n)
        Distance from the origin to each actuator's facet pair, N.

    Returns
    -------
    ndarray of int, shape (...)
        The nearest facet's actuator, or ``BOTTLENECK_TIE``.
    """
    dist = np.asarray(dist, float)
    n = dist.shape[-1]
    if n < 2:
        return np.argmin(dist, axis=-1)
    with np.errstate(invalid="ignore", over="ignore"):
        level = np.min(dist, axis=-1) * (1.0 + tie_tolerance(n))
        # Count the facets within the level, and sum their indices: with exactly one, that sum
        # is the argmin. Elementwise over columns: faster than argmin along a short axis.
        close = dist[..., 0] <= level
        count = close.astype(np.int8)
        index = np.zeros(count.shape, np.intp)
        for k in range(1, n):
            close = dist[..., k] <= level
            count += close
            index += k * close
    return np.where(count > 1, BOTTLENECK_TIE, index)


def reference_forces(jac: ArrayLike, *, torque_limits: ArrayLike, torque_min: ArrayLike | None = None,
                     torque_bias: ArrayLike | None = None) -> FloatArray:
    """``R = J^-T diag(t)``: column u is the force of actuator u at full torque (eq. 3, 5), (..., n, n).

    ``nan`` where J is singular or not finite. With ``torque_min`` or ``torque_bias`` (range
    ``[lo, hi]``) the half-edges ``J^-T diag((hi - lo) / 2)`` of the shifted parallelepiped,
    whose vertices are ``polytope_centre + R s``; a centred range gives the symmetric ``R``.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., n, n)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 3-6.

    Examples
    --------
    >>> reference_forces([[1.0, 1.0], [1.0, 2.0]], torque_limits=[1.0, 2.0]).tolist()
    [[2.0, -2.0], [-1.0, 2.0]]
    """
    jac = as_jacobian(jac)
    asym = asymmetric_range(jac, None, torque_limits, torque_min, torque_bias)
    if isinstance(asym, tuple):
        t = 0.5 * (asym[1] - asym[0])
    else:
        t = actuator_limits("torque_limits", torque_limits if asym is None else asym, jac.shape[-1])
    inv_t, _ = inverse_transpose(jac)
    with np.errstate(over="ignore"):     # beyond 1.8e308 N: inf (not representable)
        return inv_t * t[..., None, :]


def polytope_centre(jac: ArrayLike, *, torque_limits: ArrayLike, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Centre ``J^-T (hi + lo) / 2`` of the (shifted) parallelepiped, shape (..., n), N.

    0 for the symmetric set; ``nan`` where J is singular or not finite.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n)
        Joint torque limits (the upper limit with ``torque_min``), N m.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., n)
        N.

    Examples
    --------
    >>> polytope_centre(np.eye(2), torque_limits=[1.0, 2.0], torque_min=[0.0, -2.0]).tolist()
    [0.5, 0.0]
    """
    jac = as_jacobian(jac)
    lo, hi = torque_range(torque_limits, n=jac.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    inv_t, _ = inverse_transpose(jac)
    return matvecs(inv_t, (0.5 * lo + 0.5 * hi)[..., None, :])[..., 0, :]


def anisotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                      ref: ArrayLike | None = None, torque_min: ArrayLike | None = None,
                      torque_bias: ArrayLike | None = None) -> FloatArray:
    """Maximum anisotropic force (paper 000 eq. 6): the largest vertex norm of P, shape (...), N.

    ``max_s |R s|`` over sign vectors ``s``, evaluated as ``sqrt(s^T (R^T R) s)`` on one of
    each +-pair. ``inf`` where J is singular (P is unbounded), ``nan`` where J is not finite.
    Pass ``ref`` (``reference_forces``) to reuse it; ``jac`` then only tells the two apart.

    With ``torque_min`` or ``torque_bias`` (range ``[lo, hi]``, the shifted parallelepiped
    ``{f : lo <= J^T f <= hi}``) the largest norm over all ``2^n`` vertices ``J^-T v``,
    ``v_u`` in ``{lo_u, hi_u}`` (no +- pairs now); ``jac`` is then needed and ``ref`` is not
    accepted.

    Parameters
    ----------
    jac : array_like, shape (..., n, n), optional
        Square Jacobians; with ``ref``, only used to tell singular from non-finite.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m (not used with ``ref``).
    ref : array_like, shape (..., m, n), optional
        ``reference_forces(jac, torque_limits=...)`` already computed, N.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (...)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 6.

    Examples
    --------
    >>> anisotropic_force(np.eye(2), torque_limits=[3.0, 4.0]).tolist()
    5.0
    >>> anisotropic_force(np.eye(2), torque_limits=[3.0, 4.0], torque_bias=[-1.0, 0.0]).tolist()
    5.656854249492381
    """
    if torque_min is not None or torque_bias is not None:
        if ref is not None:
            raise ValueError("ref is the symmetric set's reference forces: with torque_min or torque_bias "
                             "pass jac and not ref")
        if jac is None:
            raise ValueError("jac is needed with torque_min or torque_bias")
        asym = asymmetric_range(jac, None, torque_limits, torque_min, torque_bias)
        if isinstance(asym, tuple):
            return _max_shifted_vertex_norm(jac, *asym)
        torque_limits = asym
    if ref is None:
        ref = reference_forces(jac, torque_limits=torque_limits)
    ref = np.asarray(ref, float)
    ref_ok = np.all(np.isfinite(ref), axis=(-2, -1))
    finite_j = np.all(np.isfinite(as_jacobian(jac)), axis=(-2, -1)) if jac is not None else True
    safe = ref if ref_ok.all() else np.where(ref_ok[..., None, None], ref, 0.0)
    out, diagonal = _max_vertex_norm(safe)
    # Far from unit scale (the trace of R^T R over- or underflowed, e.g. torques of 1e-300 N m)
    # redo those R scaled by a power of two, exactly, and scale back.
    lo, hi = _SAFE_SUM_SQ
    with np.errstate(invalid="ignore"):
        redo = np.array(~((diagonal > lo) & (diagonal < hi)) & ref_ok)
    if np.any(redo):
        sub = safe[redo]
        e = pow2_exponents(sub, axis=(-2, -1))
        out[redo] = np.ldexp(_max_vertex_norm(np.ldexp(sub, -e[:, None, None]))[0], e)
    return np.where(ref_ok, out, np.where(finite_j, np.inf, np.nan))


def _shifted_vertices(jac: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """``J^-T v`` (..., 2^n, m) for ``v_u = hi_u`` where ``sign_patterns(n)`` has +1, else ``lo_u``."""
    inv_t, _ = inverse_transpose(jac)
    s = sign_patterns(jac.shape[-1])
    v = np.where(s > 0, hi[..., None, :], lo[..., None, :])             # (..., 2^n, n)
    return matvecs(inv_t, v)


def matvecs(mat: FloatArray, vecs: FloatArray) -> FloatArray:
    """``mat @ v`` (..., k, m) for matrices (..., m, n) and rows ``v`` (..., k, n), summed in column
    order elementwise, so a batch gives the same bits as one matrix at a time."""
    with np.errstate(over="ignore", invalid="ignore"):
        acc = mat[..., None, :, 0] * vecs[..., :, None, 0]
        for j in range(1, mat.shape[-1]):
            acc = acc + mat[..., None, :, j] * vecs[..., :, None, j]
    return acc


def _max_shifted_vertex_norm(jac: ArrayLike, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Largest vertex norm (...) of ``{f : lo <= J^T f <= hi}``; ``inf`` singular, ``nan`` not finite J."""
    jac = as_jacobian(jac)
    verts = _shifted_vertices(jac, lo, hi)
    ok = np.all(np.isfinite(verts), axis=(-2, -1))
    finite_j = np.all(np.isfinite(jac), axis=(-2, -1))
    safe = np.where(ok[..., None, None], verts, 0.0)
    # Scaled by a power of two (exact) so that the squares neither over- nor underflow.
    e = pow2_exponents(safe, axis=(-2, -1))
    scaled = np.ldexp(safe, -e[..., None, None])
    with np.errstate(over="ignore", under="ignore"):
        out = np.ldexp(np.sqrt(np.max(np.sum(scaled * scaled, axis=-1), axis=-1)), e)
    return np.where(ok, out, np.where(finite_j, np.inf, np.nan))


def _max_vertex_norm(ref: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``max_s |R s|`` (...) for finite ``R`` (..., m, n), and the trace of ``R^T R`` (...)."""
    with np.errstate(over="ignore", invalid="ignore"):       # outside the safe scale: redone
        g = gram(components(ref))
        n = g.shape[0]
        diagonal = sum(g[i, i] for i in range(n))
        best = np.zeros(ref.shape[:-2])
        # |R s|^2 = sum_i G_ii + 2 sum_{i<j} s_i s_j G_ij, over one sign vector of each +-pair.
        for s in sign_patterns(n, half=True):
            value = diagonal.copy()
            for i in range(n):
                for j in range(i + 1, n):
                    value += (2.0 * s[i] * s[j]) * g[i, j]
            best = np.maximum(best, value)
        return np.array(np.sqrt(best)), diagonal      # an array even for one matrix


def polytope_vertices(jac: ArrayLike, *, torque_limits: ArrayLike, torque_min: ArrayLike | None = None,
                      torque_bias: ArrayLike | None = None) -> FloatArray:
    """All ``2^n`` vertices ``J^-T diag(t) s`` of P, shape (..., 2^n, m), rows as PyVista expects.

    Row k belongs to the sign vector ``sign_patterns(n)[k]``. ``nan`` where J is singular.
    With ``torque_min`` or ``torque_bias`` (range ``[lo, hi]``): ``J^-T v`` with ``v_u = hi_u``
    where the sign is +1 and ``lo_u`` where it is -1, so ``parallelepiped_faces`` still applies.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n)
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m.
    torque_min : array_like, shape (..., n), optional
        Lower joint torque limits, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque the joints already spend, N m; default 0.

    Returns
    -------
    ndarray, shape (..., 2^n, m)
        N.

    Examples
    --------
    >>> polytope_vertices(np.eye(2), torque_limits=[1.0, 2.0]).tolist()
    [[1.0, 2.0], [1.0, -2.0], [-1.0, 2.0], [-1.0, -2.0]]
    >>> polytope_vertices(np.eye(2), torque_limits=[1.0, 2.0], torque_min=[0.0, -2.0]).tolist()
    [[1.0, 2.0], [1.0, -2.0], [0.0, 2.0], [0.0, -2.0]]
    """
    if torque_min is not None or torque_bias is not None:
        asym = asymmetric_range(jac, None, torque_limits, torque_min, torque_bias)
        if isinstance(asym, tuple):
            return _shifted_vertices(as_jacobian(jac), *asym)
        torque_limits = asym
    ref = reference_forces(jac, torque_limits=torque_limits)
    return np.einsum("...ij,kj->...ki", ref, sign_patterns(ref.shape[-1]))


def parallelepiped_faces(n: int) -> list[tuple[int, ...]]:
    """Faces of the ``2^n`` vertices of ``polytope_vertices`` as vertex-index cycles.

    ``n = 3``: six quadrilaterals, ordered around each face. ``n = 2``: one polygon.

    Parameters
    ----------
    n : int
        Number of actuators, 2 or 3.

    Returns
    -------
    list of tuple of int
        Indices into the rows of ``polytope_vertices``.

    Raises
    ------
    ValueError
        For ``n`` other than 2 or 3.

    Examples
    --------
    >>> parallelepiped_faces(2)
    [(0, 2, 3, 1)]
    >>> len(parallelepiped_faces(3))
    6
    """
    patterns = sign_patterns(n)
    index = {tuple(p): k for k, p in enumerate(patterns)}
    if n == 2:
        return [tuple(index[p] for p in [(1, 1), (-1, 1), (-1, -1), (1, -1)])]
    if n != 3:
        raise ValueError(f"faces are listed for n = 2 or 3 actuators, got n = {n}")
    faces = []
    for axis in range(3):
        a, b = [i for i in range(3) if i != axis]
        for fixed in (1.0, -1.0):
            cycle = []
            for sa, sb in [(1, 1), (-1, 1), (-1, -1), (1, -1)]:
                s = [0.0] * 3
                s[axis], s[a], s[b] = fixed, sa, sb
                cycle.append(index[tuple(s)])
            faces.append(tuple(cycle))
    return faces


def isotropic_force_cross_product(jac: ArrayLike, *, torque_limits: ArrayLike) -> FloatArray:
    """Paper 000 eq. 7-8 as printed, for comparison only (3 x 3): ``min |R_u . N_u| / |N_u|``.

    ``N_1 = R_2 x R_3`` etc. loses accuracy when reference forces are nearly parallel; use
    ``isotropic_force`` instead.

    Parameters
    ----------
    jac : array_like, shape (..., 3, 3)
        Jacobians.
    torque_limits : array_like, shape (..., 3)
        Joint torque limits ``t``, N m.

    Returns
    -------
    ndarray, shape (...)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 7-8.
    """
    ref = reference_forces(jac, torque_limits=torque_limits)
    if ref.shape[-2:] != (3, 3):
        raise ValueError(f"the cross-product formula needs 3 x 3 Jacobians, got {ref.shape[-2:]}")
    r = [ref[..., :, u] for u in range(3)]
    dists = []
    for u in range(3):
        normal = np.cross(r[(u + 1) % 3], r[(u + 2) % 3])
        with np.errstate(divide="ignore", invalid="ignore"):
            dists.append(np.abs(np.einsum("...i,...i->...", r[u], normal)) / np.linalg.norm(normal, axis=-1))
    return np.min(np.stack(dists, -1), axis=-1)


def clamp_force(desired: ArrayLike, radius: ArrayLike) -> FloatArray:
    """Paper 000 eq. 9: ``F_d`` if ``|F_d| < r``, else ``F_d / |F_d| * r``, shape (..., m).

    Parameters
    ----------
    desired : array_like, shape (..., m)
        Desired forces ``F_d``, N.
    radius : array_like, shape (...)
        Isotropic force radius ``r``, N.

    Returns
    -------
    ndarray, shape (..., m)
        N.

    References
    ----------
    Łącki, Rossa and Gallacher (paper 000), eq. 9.

    Examples
    --------
    >>> clamp_force([[3.0, 4.0], [0.3, 0.4]], 1.0).tolist()
    [[0.6, 0.8], [0.3, 0.4]]
    """
    f = np.asarray(desired, float)
    r = np.asarray(radius, float)[..., None]
    norm = np.linalg.norm(f, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = f / norm * r
    return np.where(norm < r, f, scaled)
