"""Maximum anisotropic force (paper 000 eq. 6): the largest vertex norm of the force parallelepiped.

``max_s |R s|`` over sign vectors ``s`` (``R = J^-T diag(t)``, ``metrics.parallelepiped``),
evaluated as ``sqrt(s^T (R^T R) s)`` on one of each +-pair: no vertex list is formed, and
``R^T R`` too far from unit scale is redone scaled by a power of two (exact). With asymmetric
limits or a torque bias the set is shifted and has no +- symmetry: the largest norm over all
``2^n`` vertices ``J^-T v``, ``v_u`` in ``{lo_u, hi_u}``.

``inf`` where J is singular (the set is unbounded), ``nan`` where J is not finite.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .columns import SAFE_SUM_SQ
from .linalg import as_jacobian, components, gram, pow2_exponents
from .parallelepiped import reference_forces, shifted_vertices
from .torque_box import TorqueSet, sign_patterns, torque_set


def anisotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike | TorqueSet,
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
    torque_limits : array_like, shape (..., n), or TorqueSet
        Joint torque limits ``t`` (the upper limit with ``torque_min``), N m (not used with ``ref``);
        a ``TorqueSet`` is taken as it is (``metrics.torque_box``).
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
    given = isinstance(torque_limits, TorqueSet) and torque_limits.shifted
    if given or torque_min is not None or torque_bias is not None:
        if ref is not None:
            raise ValueError("ref is the symmetric set's reference forces: with torque_min or torque_bias "
                             "pass jac and not ref")
        if jac is None:
            raise ValueError("jac is needed with torque_min or torque_bias")
        jac = as_jacobian(jac)
        torque_limits = torque_set(torque_limits, n=jac.shape[-1], torque_min=torque_min, torque_bias=torque_bias)
        if torque_limits.centred_limits is None:
            return _max_shifted_vertex_norm(jac, torque_limits.lower, torque_limits.upper)
    if ref is None:
        ref = reference_forces(jac, torque_limits=torque_limits)
    ref = np.asarray(ref, float)
    ref_ok = np.all(np.isfinite(ref), axis=(-2, -1))
    finite_j = np.all(np.isfinite(as_jacobian(jac)), axis=(-2, -1)) if jac is not None else True
    safe = ref if ref_ok.all() else np.where(ref_ok[..., None, None], ref, 0.0)
    out, diagonal = _max_vertex_norm(safe)
    # Far from unit scale (the trace of R^T R over- or underflowed, e.g. torques of 1e-300 N m)
    # redo those R scaled by a power of two, exactly, and scale back.
    lo, hi = SAFE_SUM_SQ
    with np.errstate(invalid="ignore"):
        redo = np.array(~((diagonal > lo) & (diagonal < hi)) & ref_ok)
    if np.any(redo):
        sub = safe[redo]
        e = pow2_exponents(sub, axis=(-2, -1))
        out[redo] = np.ldexp(_max_vertex_norm(np.ldexp(sub, -e[:, None, None]))[0], e)
    return np.where(ref_ok, out, np.where(finite_j, np.inf, np.nan))


def _max_shifted_vertex_norm(jac: ArrayLike, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Largest vertex norm (...) of ``{f : lo <= J^T f <= hi}``; ``inf`` singular, ``nan`` not finite J."""
    jac = as_jacobian(jac)
    verts = shifted_vertices(jac, lo, hi)
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
