"""The force parallelepiped of a square Jacobian: reference forces, centre, vertices and faces.

For a square J the forces the device holds with ``|tau_u| <= t_u`` form the parallelepiped
``P = {f : |J[:, u] . f| <= t_u}`` (paper 000 sec. 2). Its vertices are
``J^-T (+-t_1, ..., +-t_n)``; the columns of ``R = J^-T diag(t)`` are the paper's reference
forces (eq. 3-6). With asymmetric limits or a torque bias (range ``[lo, hi]``,
``metrics.torque_box.torque_range``) it is shifted: half-edges ``J^-T diag((hi - lo) / 2)``
about the centre ``J^-T (hi + lo) / 2``, vertices ``J^-T v`` with ``v_u`` in ``{lo_u, hi_u}``.

=========================  ============================================  ======================
function                   what it returns                               paper 000
=========================  ============================================  ======================
``reference_forces``       ``R = J^-T diag(t)`` (half-edges when         eq. 3-6
                           shifted), (..., n, n)
``polytope_centre``        ``J^-T (hi + lo) / 2``, 0 when symmetric      --
``polytope_vertices``      all ``2^n`` vertices as rows (..., 2^n, m)    sec. 2
``parallelepiped_faces``   vertex-index cycles of the faces (n = 2, 3)   --
``shifted_vertices``       the vertices of ``{f : lo <= J^T f <= hi}``   --
``matvecs``                ``mat @ v`` for many rows, batch-exact        --
=========================  ============================================  ======================

The largest vertex norm (anisotropic force) is ``metrics.anisotropy``; the distances to the
facets (isotropic force) are ``metrics.isotropy``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian, inverse_transpose
from .torque_box import TorqueSet, sign_patterns, torque_set


def reference_forces(jac: ArrayLike, *, torque_limits: ArrayLike | TorqueSet, torque_min: ArrayLike | None = None,
                     torque_bias: ArrayLike | None = None) -> FloatArray:
    """``R = J^-T diag(t)``: column u is the force of actuator u at full torque (eq. 3, 5), (..., n, n).

    ``nan`` where J is singular or not finite. With ``torque_min`` or ``torque_bias`` (range
    ``[lo, hi]``) the half-edges ``J^-T diag((hi - lo) / 2)`` of the shifted parallelepiped,
    whose vertices are ``polytope_centre + R s``; a centred range gives the symmetric ``R``.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
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
    box = torque_set(torque_limits, n=jac.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    t = box.half_width if box.centred_limits is None else box.centred_limits
    inv_t, _ = inverse_transpose(jac)
    with np.errstate(over="ignore"):     # beyond 1.8e308 N: inf (not representable)
        return inv_t * t[..., None, :]


def polytope_centre(jac: ArrayLike, *, torque_limits: ArrayLike | TorqueSet, torque_min: ArrayLike | None = None,
                    torque_bias: ArrayLike | None = None) -> FloatArray:
    """Centre ``J^-T (hi + lo) / 2`` of the (shifted) parallelepiped, shape (..., n), N.

    0 for the symmetric set; ``nan`` where J is singular or not finite.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
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
    box = torque_set(torque_limits, n=jac.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    inv_t, _ = inverse_transpose(jac)
    return matvecs(inv_t, (0.5 * box.lower + 0.5 * box.upper)[..., None, :])[..., 0, :]


def polytope_vertices(jac: ArrayLike, *, torque_limits: ArrayLike | TorqueSet, torque_min: ArrayLike | None = None,
                      torque_bias: ArrayLike | None = None) -> FloatArray:
    """All ``2^n`` vertices ``J^-T diag(t) s`` of P, shape (..., 2^n, m), rows as PyVista expects.

    Row k belongs to the sign vector ``sign_patterns(n)[k]``. ``nan`` where J is singular.
    With ``torque_min`` or ``torque_bias`` (range ``[lo, hi]``): ``J^-T v`` with ``v_u = hi_u``
    where the sign is +1 and ``lo_u`` where it is -1, so ``parallelepiped_faces`` still applies.

    Parameters
    ----------
    jac : array_like, shape (..., n, n)
        Square Jacobians.
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m; a ``TorqueSet`` is
        taken as it is (``metrics.torque_box``).
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
    jac = as_jacobian(jac)
    box = torque_set(torque_limits, n=jac.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
    if box.centred_limits is None:
        return shifted_vertices(jac, box.lower, box.upper)
    ref = reference_forces(jac, torque_limits=box)
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


def shifted_vertices(jac: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Vertices ``J^-T v`` of ``{f : lo <= J^T f <= hi}``, shape (..., 2^n, m): ``v_u = hi_u`` or ``lo_u``.

    Row k takes ``v_u = hi_u`` where ``sign_patterns(n)[k]`` has +1 and ``lo_u`` where it has
    -1, so ``parallelepiped_faces`` applies. ``nan`` where J is singular or not finite. The
    arguments are taken as given (no validation): ``polytope_vertices`` is the checked entry.

    Parameters
    ----------
    jac : ndarray, shape (..., n, n)
        Square Jacobians, float64.
    lo, hi : ndarray, shape (..., n)
        Usable torque range (``metrics.torque_box.torque_range``), N m.

    Returns
    -------
    ndarray, shape (..., 2^n, m)
        N.

    Examples
    --------
    >>> shifted_vertices(np.eye(2), np.array([0.0, -2.0]), np.array([1.0, 2.0])).tolist()
    [[1.0, 2.0], [1.0, -2.0], [0.0, 2.0], [0.0, -2.0]]
    """
    inv_t, _ = inverse_transpose(jac)
    s = sign_patterns(jac.shape[-1])
    v = np.where(s > 0, hi[..., None, :], lo[..., None, :])             # (..., 2^n, n)
    return matvecs(inv_t, v)


def matvecs(mat: FloatArray, vecs: FloatArray) -> FloatArray:
    """``mat @ v`` for every row ``v``, shape (..., k, m), summed in column order elementwise.

    ``np.matmul`` may pick a different summation order (and SIMD path) for a batch than for one
    matrix; this sum runs over the columns in order, so a batch gives the same bits as one
    matrix at a time. Overflow gives ``inf`` silently.

    Parameters
    ----------
    mat : ndarray, shape (..., m, n)
        Matrices.
    vecs : ndarray, shape (..., k, n)
        Vectors as rows.

    Returns
    -------
    ndarray, shape (..., k, m)
        Row i is ``mat @ vecs[..., i, :]``.

    Examples
    --------
    >>> matvecs(np.array([[1.0, 2.0], [0.0, 1.0]]), np.array([[1.0, 1.0], [2.0, 0.0]])).tolist()
    [[3.0, 1.0], [2.0, 0.0]]
    """
    with np.errstate(over="ignore", invalid="ignore"):
        acc = mat[..., None, :, 0] * vecs[..., :, None, 0]
        for j in range(1, mat.shape[-1]):
            acc = acc + mat[..., None, :, j] * vecs[..., :, None, j]
    return acc
