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
is the zonotope ``A [-t, t]^n``; ``zonotope_*`` handle it.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.base import FloatArray

from .ellipsoids import actuator_limits
from .linalg import as_jacobian, components, gram, inverse_transpose


#: Bottleneck codes besides an actuator index (``-1`` is an infeasible point, see ``evaluate``):
#: two or more actuators' facets are equally near the origin within rounding (a tie), or the
#: actuation is redundant and no single actuator caps the isotropic force (shared).
BOTTLENECK_INFEASIBLE = -1
BOTTLENECK_TIE = -2
BOTTLENECK_SHARED = -3


def sign_patterns(n: int, *, half: bool = False) -> FloatArray:
    """All ``2^n`` sign vectors (rows, shape (2^n, n)); ``half`` keeps one of each +-pair."""
    rows = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    return rows[rows[:, 0] > 0] if half else rows


def column_norms(jac: ArrayLike) -> FloatArray:
    """Euclidean norm of each Jacobian column, shape (..., n); ``inf`` for a non-finite column."""
    a = components(as_jacobian(jac))
    acc = a[0] * a[0]
    for k in range(1, a.shape[0]):
        acc += a[k] * a[k]
    with np.errstate(invalid="ignore"):
        norms = np.moveaxis(np.sqrt(acc), 0, -1)
    return np.where(np.isnan(norms), np.inf, norms)


def facet_distances(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                    norms: ArrayLike | None = None) -> FloatArray:
    """Distance ``t_u / |J[:, u]|`` from the origin to each facet pair of P, shape (..., n), in N.

    A zero column (the actuator's joint cannot move the end-effector) gives ``inf``: that
    actuator limits no direction.
    """
    norms = column_norms(jac) if norms is None else np.asarray(norms, float)
    t = actuator_limits("torque_limits", torque_limits, norms.shape[-1])
    with np.errstate(divide="ignore"):
        return t / norms


def isotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                    norms: ArrayLike | None = None) -> FloatArray:
    """Maximum isotropic force (paper 000 eq. 8): radius of the largest ball about 0 in P, shape (...).

    ``min_u t_u / |J[:, u]|``, equal to eq. 8's ``min_u |R_u . N_u| / |N_u|`` but with no
    inverse: finite at singularities, zero where J is unbounded (a direct singularity).
    """
    return np.min(facet_distances(jac, torque_limits=torque_limits, norms=norms), axis=-1)


def bottleneck_actuator(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                        norms: ArrayLike | None = None) -> np.ndarray:
    """Index of the actuator whose facet is nearest the origin (limits isotropy), shape (...), int."""
    return np.argmin(facet_distances(jac, torque_limits=torque_limits, norms=norms), axis=-1)


def reference_forces(jac: ArrayLike, *, torque_limits: ArrayLike) -> FloatArray:
    """``R = J^-T diag(t)``: column u is the force of actuator u at full torque (eq. 3, 5), (..., n, n).

    ``nan`` where J is singular or not finite.
    """
    jac = as_jacobian(jac)
    t = actuator_limits("torque_limits", torque_limits, jac.shape[-1])
    inv_t, _ = inverse_transpose(jac)
    return inv_t * t[..., None, :]


def anisotropic_force(jac: ArrayLike | None = None, *, torque_limits: ArrayLike,
                      ref: ArrayLike | None = None) -> FloatArray:
    """Maximum anisotropic force (paper 000 eq. 6): the largest vertex norm of P, shape (...), N.

    ``max_s |R s|`` over sign vectors ``s``, evaluated as ``sqrt(s^T (R^T R) s)`` on one of
    each +-pair. ``inf`` where J is singular (P is unbounded), ``nan`` where J is not finite.
    Pass ``ref`` (``reference_forces``) to reuse it; ``jac`` then only tells the two apart.
    """
    if ref is None:
        ref = reference_forces(jac, torque_limits=torque_limits)
    ref = np.asarray(ref, float)
    ref_ok = np.all(np.isfinite(ref), axis=(-2, -1))
    finite_j = np.all(np.isfinite(as_jacobian(jac)), axis=(-2, -1)) if jac is not None else True
    g = gram(components(ref if ref_ok.all() else np.where(ref_ok[..., None, None], ref, 0.0)))
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
    out = np.sqrt(best)
    return np.where(ref_ok, out, np.where(finite_j, np.inf, np.nan))


def polytope_vertices(jac: ArrayLike, *, torque_limits: ArrayLike) -> FloatArray:
    """All ``2^n`` vertices ``J^-T diag(t) s`` of P, shape (..., 2^n, m), rows as PyVista expects.

    Row k belongs to the sign vector ``sign_patterns(n)[k]``. ``nan`` where J is singular.
    """
    ref = reference_forces(jac, torque_limits=torque_limits)
    return np.einsum("...ij,kj->...ki", ref, sign_patterns(ref.shape[-1]))


def parallelepiped_faces(n: int) -> list[tuple[int, ...]]:
    """Faces of the ``2^n`` vertices of ``polytope_vertices`` as vertex-index cycles.

    ``n = 3``: six quadrilaterals, ordered around each face. ``n = 2``: one polygon.
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
    """Paper 000 eq. 9: ``F_d`` if ``|F_d| < r``, else ``F_d / |F_d| * r``, shape (..., m)."""
    f = np.asarray(desired, float)
    r = np.asarray(radius, float)[..., None]
    norm = np.linalg.norm(f, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = f / norm * r
    return np.where(norm < r, f, scaled)


# -- redundant actuation: zonotopes ------------------------------------------------------
@dataclass(frozen=True)
class Zonotope:
    """Force zonotope ``A [-t, t]^n``: facet unit normals (..., k, m), support values (..., k)."""

    normals: FloatArray
    offsets: FloatArray

    @property
    def inscribed_radius(self) -> FloatArray:
        """Radius of the largest ball about 0 inside, shape (...): the smallest facet offset."""
        return np.min(self.offsets, axis=-1)


def zonotope(generators: ArrayLike, *, torque_limits: ArrayLike) -> Zonotope:
    """Facets of the force set ``{A tau : |tau_u| <= t_u}`` with ``A`` (..., m, n), n >= m.

    Every facet normal is orthogonal to m - 1 generators; for each (m-1)-subset the normal is
    the generalised cross product (cofactors), and its support value is
    ``sum_u t_u |A[:, u] . nu|``. Degenerate subsets (parallel generators) give no facet.
    """
    a = as_jacobian(generators, "generators")
    m, n = a.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {a.shape}")
    t = actuator_limits("torque_limits", torque_limits, n)
    scaled = a * t[..., None, :]
    normals = []
    for subset in itertools.combinations(range(n), m - 1):
        sub = a[..., :, list(subset)]
        # Generalised cross product: component i = (-1)^i det(sub without row i).
        comps = []
        for i in range(m):
            minor = np.delete(sub, i, axis=-2)
            comps.append((-1) ** i * (np.linalg.det(minor) if m > 1 else np.ones(minor.shape[:-2])))
        normals.append(np.stack(comps, axis=-1))
    nu = np.stack(normals, axis=-2)                                   # (..., k, m)
    length = np.linalg.norm(nu, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = nu / length
    offsets = np.sum(np.abs(np.einsum("...km,...mn->...kn", unit, scaled)), axis=-1)
    offsets = np.where(length[..., 0] > 0, offsets, np.inf)         # degenerate: no facet
    return Zonotope(normals=unit, offsets=offsets)


def zonotope_vertices(generators: ArrayLike, *, torque_limits: ArrayLike) -> FloatArray:
    """The ``2^n`` signed sums ``A diag(t) s`` (..., 2^n, m): a superset of the zonotope's vertices."""
    a = as_jacobian(generators, "generators")
    t = actuator_limits("torque_limits", torque_limits, a.shape[-1])
    return np.einsum("...ij,kj->...ki", a * t[..., None, :], sign_patterns(a.shape[-1]))
