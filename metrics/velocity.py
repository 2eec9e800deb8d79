"""Velocity capability under joint speed limits: the velocity polytope and its inscribed ball.

=========================  ==============================================  ===========================
quantity                   definition                                      computed as
=========================  ==============================================  ===========================
joint speed limit          motor speed over the transmission ratio,        ``joint_speed_limits``
                           ``qdot_max_u = omega_max_u / N_u``
velocity polytope          ``{J qdot : qdot_min <= qdot <= qdot_max}``     ``velocity_polytope``
                           (pycapacity ``velocity_polytope``)               (facets),
                                                                           ``velocity_polytope_vertices``
isotropic velocity         radius of the largest ball about 0 inside it:   ``isotropic_velocity``
                           the speed the handle reaches in every direction
same, from the joint       ``{v : |K v| <= qdot_max}`` (``K = dq/dx``, the ``rate_slab_radius``
rates                      force map's transpose), on ``rows`` at zero
                           rate of the other task coordinates
peak velocity per axis     fastest pure motion along task axis i:          ``peak_velocities``
                           ``min_u qdot_max_u / |K[u, i]|``
=========================  ==============================================  ===========================

The velocity polytope is the zonotope ``J [qdot_min, qdot_max]^n`` (``metrics.zonotopes`` with the
Jacobian as generators and the speed box in place of the torque box): its facet normals are
orthogonal to ``m - 1`` columns of ``J`` and its inscribed radius is the smallest facet offset,
for a square ``J`` (a parallelepiped) and a redundant one alike. No inverse is formed, so the
radius goes to 0 continuously at a singular ``J`` (the set is flat there). Speeds in m/s for a
length row of ``J``; a row in rad gives rad/s (``rows`` keeps the length rows alone: the linear
velocity with the handle turning as it may, as ``metrics.pose`` takes the velocity ellipsoid).

A closed chain's joints move at ``qdot = K xdot`` (``K = A^T``, ``A`` the force map, ``w = A tau``):
its velocity set is ``{v : |K v| <= qdot_max}``, slabs with normals the rows of ``K``, the same set
as ``J [-qdot_max, qdot_max]^n`` for a square regular ``J`` and the only right one for a redundantly
actuated model (whose ``J = K^+`` would admit joint rates the loop closures forbid).
``rate_slab_radius`` takes that form: for a device with orientation freedoms its slice at zero
angular velocity (the handle translating, as forces are taken at zero moment), finite at a direct
singularity where ``J`` is not.

References: pycapacity ``velocity_polytope`` (the peer the tests compare with); T. Yoshikawa,
*Foundations of Robotics*, 1990, on manipulability under joint rate limits.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .ellipsoids import actuator_limits
from .linalg import as_jacobian
from .torque_box import sign_patterns
from .wrench_facets import slice_inscribed_radius
from .zonotopes import Zonotope, zonotope


def joint_speed_limits(motor_speeds: ArrayLike, *, gear_ratios: ArrayLike) -> FloatArray:
    """Joint-side speed limits ``omega_max_u / N_u`` (..., n): a rotor turns ``N_u`` times faster than its joint.

    Parameters
    ----------
    motor_speeds : array_like, shape (..., n)
        Each motor's largest speed, rad/s at the motor (m/s for a linear motor).
    gear_ratios : array_like, shape (..., n)
        Transmission ratios ``N_u`` (joint torque per motor torque), positive.

    Returns
    -------
    ndarray, shape (..., n)
        rad/s at the joint (m/s for a prismatic joint).

    Examples
    --------
    >>> joint_speed_limits([508.9, 508.9], gear_ratios=[13.3, 11.2]).round(2).tolist()
    [38.26, 45.44]
    """
    speeds = np.asarray(motor_speeds, float)
    ratios = actuator_limits("gear_ratios", gear_ratios, np.shape(gear_ratios)[-1])
    speeds = actuator_limits("motor_speeds", speeds, ratios.shape[-1])
    return speeds / ratios


def _speed_box(jac: FloatArray, joint_speed_limits, joint_speed_min):
    """The validated speed box: limits (..., n) and the lower limits or None."""
    n = jac.shape[-1]
    hi = actuator_limits("joint_speed_limits", joint_speed_limits, n)
    if joint_speed_min is None:
        return hi, None
    lo = np.asarray(joint_speed_min, float)
    if lo.shape[-1:] != (n,) or not np.all(np.isfinite(lo)) or np.any(lo >= hi):
        raise ValueError(f"joint_speed_min must be {n} finite values below joint_speed_limits (rad/s), "
                         f"got {joint_speed_min!r}")
    return hi, lo


def velocity_polytope(jac: ArrayLike, *, joint_speed_limits: ArrayLike,
                      joint_speed_min: ArrayLike | None = None) -> Zonotope:
    """Facets of ``{J qdot : qdot_min <= qdot <= qdot_max}`` (``J`` (..., m, n), n >= m): unit normals and offsets.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        n >= m.
    joint_speed_limits : array_like, shape (..., n)
        ``qdot_max``, rad/s (m/s for a prismatic joint), positive.
    joint_speed_min : array_like, shape (..., n), optional
        ``qdot_min``; default ``-qdot_max``.

    Returns
    -------
    Zonotope
        ``normals`` (..., k, m) and ``offsets`` (..., k) in m/s: the set is ``{v : |normals v| <= offsets}``;
        with ``joint_speed_min`` each normal appears twice, ``+nu`` then ``-nu``, and it is
        ``{v : normals v <= offsets}`` (``metrics.zonotopes.zonotope``).

    Examples
    --------
    >>> p = velocity_polytope(np.eye(2), joint_speed_limits=[1.0, 2.0])
    >>> sorted(p.offsets.tolist())
    [1.0, 2.0]
    """
    a = as_jacobian(jac, "jac")
    hi, lo = _speed_box(a, joint_speed_limits, joint_speed_min)
    return zonotope(a, torque_limits=hi, torque_min=lo)


def velocity_polytope_vertices(jac: ArrayLike, *, joint_speed_limits: ArrayLike,
                               joint_speed_min: ArrayLike | None = None) -> FloatArray:
    """``J qdot`` at the ``2^n`` corners of the speed box (..., 2^n, m), m/s; the polytope is their hull.

    For a square, regular ``J`` every corner's image is a vertex (a parallelepiped); for a
    redundant one (n > m) they are a superset of the vertices. Corner ``k`` takes
    ``qdot_max[u]`` where ``sign_patterns(n)[k, u] > 0``, ``qdot_min[u]`` elsewhere.

    Parameters are those of ``velocity_polytope``.

    Returns
    -------
    ndarray, shape (..., 2^n, m)

    Examples
    --------
    >>> velocity_polytope_vertices(np.eye(2), joint_speed_limits=[1.0, 2.0]).tolist()
    [[1.0, 2.0], [1.0, -2.0], [-1.0, 2.0], [-1.0, -2.0]]
    """
    a = as_jacobian(jac, "jac")
    hi, lo = _speed_box(a, joint_speed_limits, joint_speed_min)
    lo = -hi if lo is None else lo
    corners = np.where(sign_patterns(a.shape[-1]) > 0, hi[..., None, :], lo[..., None, :])   # (..., 2^n, n)
    return np.einsum("...mn,...kn->...km", a, corners)


def isotropic_velocity(jac: ArrayLike, *, joint_speed_limits: ArrayLike,
                       joint_speed_min: ArrayLike | None = None) -> FloatArray:
    """The largest speed the handle reaches in every direction (...), m/s: the velocity polytope's inscribed radius.

    The smallest facet offset of ``velocity_polytope``; 0 where ``J`` loses rank (the set is
    flat: every facet is degenerate or has offset 0) and where the origin lies outside the box's
    image (``joint_speed_min`` above 0). ``nan`` for a non-finite ``J``.

    Parameters are those of ``velocity_polytope``.

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> float(isotropic_velocity([[2.0, 0.0], [0.0, 0.5]], joint_speed_limits=[1.0, 1.0]))
    0.5
    >>> isotropic_velocity(np.stack([np.eye(2), [[1.0, 1.0], [1.0, 1.0]]]), joint_speed_limits=[1.0, 1.0]).tolist()
    [1.0, 0.0]
    """
    a = as_jacobian(jac, "jac")
    finite = np.all(np.isfinite(a), axis=(-2, -1))
    safe = np.where(finite[..., None, None], a, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        poly = velocity_polytope(safe, joint_speed_limits=joint_speed_limits, joint_speed_min=joint_speed_min)
    # Every facet degenerate (offset inf): no m - 1 independent columns, a flat set.
    radius = np.where(np.all(np.isinf(poly.offsets), axis=-1), 0.0, poly.inscribed_radius)
    return np.where(finite, radius, np.nan)


def rate_slab_radius(inverse_jacobian: ArrayLike, *, joint_speed_limits: ArrayLike, rows=None) -> FloatArray:
    """Largest speed in every direction of ``rows`` with the joint rates ``qdot = K v`` in their box (...), m/s.

    The set ``{v : |K[u] . v| <= qdot_max_u}`` sliced on ``rows`` (the other task rates 0): the
    radius ``min_u qdot_max_u / |K[u, rows]|`` (``wrench_facets.slice_inscribed_radius``, scaled
    against over- and underflow). 0 where a row of ``K`` is infinite (an inverse singularity: a
    joint would have to turn infinitely fast), ``nan`` where ``K`` is ``nan``.

    Parameters
    ----------
    inverse_jacobian : array_like, shape (..., n, m)
        ``K = dq/dx`` (the force map transposed), rad/m or rad/rad.
    joint_speed_limits : array_like, shape (..., n)
        ``qdot_max``, rad/s (m/s for a prismatic joint), positive.
    rows : sequence of int, optional
        The task rows of the slice; default all.

    Returns
    -------
    ndarray, shape (...)
        In the unit of the rows' rates (m/s for length rows).

    Examples
    --------
    >>> float(rate_slab_radius(np.linalg.inv([[2.0, 0.0], [0.0, 0.5]]), joint_speed_limits=[1.0, 1.0]))
    0.5
    """
    k = np.asarray(inverse_jacobian, float)
    if k.ndim < 2:
        raise ValueError(f"inverse_jacobian must be (..., n, m), got shape {k.shape}")
    hi = actuator_limits("joint_speed_limits", joint_speed_limits, k.shape[-2])
    rows = list(range(k.shape[-1])) if rows is None else list(rows)
    hi = np.broadcast_to(hi, k.shape[:-1])
    return slice_inscribed_radius(k, hi, rows=rows)


def peak_velocities(inverse_jacobian: ArrayLike, *, joint_speed_limits: ArrayLike) -> FloatArray:
    """Fastest pure motion along each task axis (..., m): ``min_u qdot_max_u / |K[u, i]|``.

    Along axis i alone the joints turn at ``qdot = K e_i s``; the first to reach its limit caps
    the speed ``s``. m/s for a length axis, rad/s for an angle; 0 at an inverse singularity
    (``K`` infinite), ``inf`` along an axis no joint moves for.

    Parameters
    ----------
    inverse_jacobian : array_like, shape (..., n, m)
        ``K = dq/dx``.
    joint_speed_limits : array_like, shape (..., n)
        ``qdot_max``, positive.

    Returns
    -------
    ndarray, shape (..., m)

    Examples
    --------
    >>> peak_velocities([[2.0, 0.0], [1.0, 1.0]], joint_speed_limits=[1.0, 3.0]).tolist()
    [0.5, 3.0]
    """
    k = np.asarray(inverse_jacobian, float)
    if k.ndim < 2:
        raise ValueError(f"inverse_jacobian must be (..., n, m), got shape {k.shape}")
    return np.stack([rate_slab_radius(k, joint_speed_limits=joint_speed_limits, rows=[i])
                     for i in range(k.shape[-1])], axis=-1)


@dataclass(frozen=True)
class PoseVelocity:
    """The velocity polytope at one pose. SI units.

    Attributes
    ----------
    joint_speed_limits : ndarray, shape (n,)
        ``motor_speeds / gear_ratios``, rad/s at the joints (m/s for a prismatic joint).
    vertices : ndarray, shape (k, r)
        The polytope's vertices over the task's length rows ``rows``, m/s.
    signs : ndarray, shape (k, n)
        The speed-box corner (+-1 per joint) each vertex is the image of; for a slice (a device with
        orientation freedoms) +-1 where the joint is at its limit there, 0 where it is not.
    isotropic_velocity : float
        The largest speed the handle reaches in every direction, m/s; 0 at a singular ``J``.
    rows : tuple of int
        The task rows (length coordinates) the polytope is over.
    peak_velocity : ndarray, shape (m,), or None
        Fastest pure motion along each task axis (``peak_velocities``), m/s (rad/s for an angle);
        None where not computed (``analyse_velocity`` of a bare Jacobian).
    """

    joint_speed_limits: FloatArray
    vertices: FloatArray
    signs: FloatArray
    isotropic_velocity: float
    rows: tuple[int, ...]
    peak_velocity: FloatArray | None = None


def analyse_velocity(jac: ArrayLike, *, motor_speeds: ArrayLike, gear_ratios: ArrayLike,
                     rows=None) -> PoseVelocity:
    """The velocity polytope of one Jacobian (m, n) with each motor's largest speed.

    Parameters
    ----------
    jac : array_like, shape (m, n)
    motor_speeds : array_like, shape (n,)
        rad/s at the motors.
    gear_ratios : array_like, shape (n,)
    rows : sequence of int, optional
        Task rows to keep (the length rows of a device with orientation freedoms: the linear
        velocity, the handle turning as it may); default all.

    Returns
    -------
    PoseVelocity
        Where ``J[rows]`` has full rank and more columns than rows, only the corners' images
        that are vertices of their convex hull are kept; otherwise every image.

    Examples
    --------
    >>> v = analyse_velocity(np.eye(2), motor_speeds=[2.0, 4.0], gear_ratios=[2.0, 2.0])
    >>> v.isotropic_velocity, v.vertices.shape
    (1.0, (4, 2))
    """
    a = as_jacobian(jac, "jac")
    if a.ndim != 2:
        raise ValueError(f"jac must be one matrix (m, n), got shape {a.shape}")
    rows = tuple(range(a.shape[0])) if rows is None else tuple(int(r) for r in rows)
    a = a[list(rows)]
    speeds = joint_speed_limits(motor_speeds, gear_ratios=gear_ratios)
    verts = velocity_polytope_vertices(a, joint_speed_limits=speeds)
    signs = sign_patterns(a.shape[-1])
    if a.shape[-1] > a.shape[-2] and np.all(np.isfinite(a)) and np.linalg.matrix_rank(a) == a.shape[-2]:
        from scipy.spatial import ConvexHull
        keep = np.sort(ConvexHull(verts).vertices)
        verts, signs = verts[keep], signs[keep]
    iso = float(isotropic_velocity(a, joint_speed_limits=speeds))
    return PoseVelocity(joint_speed_limits=speeds, vertices=verts, signs=signs, isotropic_velocity=iso, rows=rows)
