"""Which global maxima are infinite in truth: decided from the mechanism's singularity analysis.

A grid samples a map; it cannot tell a large finite supremum from an infinite one (the
five-bar's isotropic-force maximum jumped from 185 N at 1000 x 1000 to 667 N at 1001 x 1001).
The mechanism can: a mechanism with ``singular_loci()`` gives task points just inside its
reach next to each kind of singular locus, and where such a point is feasible and inside the
map's domain, the closure of the feasible set holds that singularity and the quantities below
tend to infinity there.

=============================  ===============================  =========================================
quantity                       unbounded next to                why
=============================  ===============================  =========================================
condition_number               any singularity                  sigma_min -> 0 (inverse) or
                                                                sigma_max -> inf (direct)
anisotropic_force              an inverse singularity           a column of J -> 0: its facet pair
                                                                moves to infinity, P becomes a slab
isotropic_force,               every actuator singular at once  min_u t_u / |J[:, u]| and
force_ellipsoid_min_radius     (``all_inverse``: J -> 0)        1 / sigma_max(J diag(1/t)) stay finite
                                                                while one column is left
spatial_resolution,            a direct singularity             max_u |J[:, u]| delta_u with J -> inf:
angular_resolution                                              the end-effector moves, no sensor counts
apparent_mass_max              an inverse singularity           J M^-1 J^T loses rank: a locked direction
mass_condition_number          any singularity                  the largest apparent mass unbounded, or
                                                                the smallest -> 0 where J -> inf
=============================  ===============================  =========================================

The other quantities (manipulability, 1 / condition number) are bounded on a bounded domain.
A mechanism without ``singular_loci`` (the Inverse3, whose Table 2 limits keep both legs away
from stretched and folded) is not claimed unbounded anywhere; its maxima are grid figures with
the grid's error estimate. Direct singularities count from the mechanism's own ``"direct"``
loci where it has them (the delta's coplanar-bars surface) and from any feasible grid point
classed direct; inverse ones likewise from the mechanism's loci and from any feasible grid
point classed inverse (the Inoue platform has no loci of its own, and its grid meets an
inverse singularity where the condition number is 10^8).
"""
from __future__ import annotations

import numpy as np

from kinematics.arrays import FloatArray
from kinematics.contract import Mechanism

#: For each quantity, the loci (``singular_loci`` keys, or ``"direct"``) next to which it is unbounded.
UNBOUNDED_NEAR: dict[str, tuple[str, ...]] = {
    "condition_number": ("inverse", "all_inverse", "direct"),
    "anisotropic_force": ("inverse", "all_inverse"),
    "isotropic_force": ("all_inverse",),
    "force_ellipsoid_min_radius": ("all_inverse",),
    # One sensor count moves the end-effector by J delta: unbounded where J is (a direct singularity).
    "spatial_resolution": ("direct",),
    "angular_resolution": ("direct",),
    # A leg stretched or folded locks a direction: the hand pushing along it moves the whole
    # device through a vanishing lever, 1 / (smallest eigenvalue of J M^-1 J^T) -> inf.
    "apparent_mass_max": ("inverse", "all_inverse"),
    "mass_condition_number": ("inverse", "all_inverse", "direct"),
}
#: How many points an unbounded figure is located at.
LOCATIONS = 10
#: A device with orientation freedoms reports the anisotropic force at zero moment: next to an
#: inverse singularity that slice of its wrench set stays bounded (the unbounded direction has
#: a moment part). The Inoue platform's tends to 28.7 N at an inverse node.
ORIENTED_BOUNDED_NEAR_INVERSE = ("anisotropic_force",)


def unbounded_near(mechanism: Mechanism) -> dict[str, tuple[str, ...]]:
    """``UNBOUNDED_NEAR`` as it holds for ``mechanism`` (``ORIENTED_BOUNDED_NEAR_INVERSE``).

    >>> from kinematics.inoue import InouePlatform
    >>> unbounded_near(InouePlatform())["anisotropic_force"]
    ('all_inverse',)
    """
    if not mechanism.has_orientation:
        return UNBOUNDED_NEAR
    return {**UNBOUNDED_NEAR, **{q: tuple(k for k in UNBOUNDED_NEAR[q] if k != "inverse")
                                 for q in ORIENTED_BOUNDED_NEAR_INVERSE}}


def finite_at_inverse(mechanism: Mechanism, names) -> tuple[str, ...]:
    """The quantities among ``names`` that keep a finite, nonzero limit where one actuator is
    singular (neither unbounded nor vanishing next to an ``"inverse"`` locus): their values at
    grid nodes classed inverse are that limit, and may be the map's extreme. The others' values
    there are rounding noise (a condition number of 10^15), decided by the tables instead."""
    unbounded = unbounded_near(mechanism)
    return tuple(q for q in names if "inverse" not in unbounded.get(q, ()) + VANISHING_NEAR.get(q, ()))


def _inside(grid, task_names: tuple[str, ...], points: FloatArray) -> np.ndarray:
    """Which task points (k, m) lie in the grid's box (varied axes) and on its fixed coordinates."""
    ok = np.ones(len(points), bool)
    fixed = dict(grid.fixed)
    for j, name in enumerate(task_names):
        if name in grid.axes:
            k = grid.axes.index(name)
            ok &= (points[:, j] >= grid.lower[k]) & (points[:, j] <= grid.upper[k])
        else:
            value = fixed.get(name, np.nan)
            ok &= np.abs(points[:, j] - value) <= 1e-12 * max(1.0, abs(value))
    return ok


def feasible_loci(mechanism: Mechanism, grid) -> dict[str, FloatArray]:
    """The mechanism's singular-locus points (k, m) that are feasible and inside the grid's domain.

    Parameters
    ----------
    mechanism : Mechanism
        The model; its ``singular_loci`` give the candidate points.
    grid : GridSpec
        The map's domain.

    Returns
    -------
    dict of str to ndarray, shape (k, m)
        By kind of singular locus; ``k`` may be 0. m.
    """
    out = {}
    for kind, points in mechanism.singular_loci().items():
        points = np.asarray(points, float).reshape(-1, mechanism.task_dim)
        points = points[_inside(grid, tuple(mechanism.task_names), points)]
        if len(points):
            q, reachable = mechanism.inverse(points)
            ok = reachable.copy()
            ok[reachable] = mechanism.feasible(q[reachable], points[reachable])
            points = points[ok]
        out[kind] = points
    return out


#: For each quantity, the loci next to which it tends to 0 (its infimum is 0 in truth, not the grid's minimum).
VANISHING_NEAR: dict[str, tuple[str, ...]] = {
    # A direct singularity: J -> inf, so a facet t_u / |J[:, u]| and 1 / sigma_max(J diag(1/t)) -> 0.
    "isotropic_force": ("direct",),
    "force_ellipsoid_min_radius": ("direct",),
    # 1 / condition number -> 0 wherever the condition number is unbounded.
    "inverse_condition_number": ("inverse", "all_inverse", "direct"),
    # The acceleration set J M^-1 (torque box) goes flat at an inverse singularity (J loses rank)
    # and where the force set does at a direct one.
    "isotropic_acceleration": ("inverse", "all_inverse", "direct"),
    # The velocity set J [-qdot_max, qdot_max]^n goes flat where J loses rank (an inverse
    # singularity); at a direct one it is unbounded along a direction, not flat.
    "isotropic_velocity": ("inverse", "all_inverse"),
}


def _near(loci: dict[str, FloatArray], table: dict[str, tuple[str, ...]], names) -> dict[str, FloatArray]:
    out = {}
    for name in names:
        hits = [loci[kind] for kind in table.get(name, ()) if len(loci.get(kind, ()))]
        if hits:
            out[name] = np.concatenate(hits)[:LOCATIONS]
    return out


def singular_extremes(mechanism: Mechanism, grid, names, *, direct_points: FloatArray | None = None,
                      inverse_points: FloatArray | None = None) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
    """``(unbounded_suprema, vanishing_infima)`` from one singularity analysis: each maps a quantity to where.

    Parameters
    ----------
    mechanism
        The model; its ``singular_loci`` (if any) decide.
    grid : GridSpec
        The map's domain.
    names : iterable of str
        Requested quantities.
    direct_points : ndarray, shape (k, m), optional
        Feasible grid points the mechanism classes as direct (or combined) singular.
    inverse_points : ndarray, shape (k, m), optional
        Feasible grid points the mechanism classes as inverse singular.

    Returns
    -------
    unbounded, vanishing : dict of str to ndarray, shape (k, m)
        Quantities whose supremum is infinite (``UNBOUNDED_NEAR``), and those whose infimum is 0
        (``VANISHING_NEAR``), at most ``LOCATIONS`` points each, in m.
    """
    loci = feasible_loci(mechanism, grid)
    for kind, points in (("direct", direct_points), ("inverse", inverse_points)):
        if points is not None and len(points):
            own = loci.get(kind, np.empty((0, np.shape(points)[-1])))
            loci[kind] = np.concatenate([np.asarray(own, float), np.asarray(points, float)])
    names = tuple(names)
    return _near(loci, unbounded_near(mechanism), names), _near(loci, VANISHING_NEAR, names)


def unbounded_suprema(mechanism: Mechanism, grid, names, *, direct_points: FloatArray | None = None
                      ) -> dict[str, FloatArray]:
    """Quantities among ``names`` whose supremum over the map's domain is infinite, with where (k, m).

    Parameters
    ----------
    mechanism
        The model; its ``singular_loci`` (if any) decide.
    grid : GridSpec
        The map's domain.
    names : iterable of str
        Requested quantities.
    direct_points : ndarray, shape (k, m), optional
        Feasible grid points the mechanism classes as direct (or combined) singular.

    Returns
    -------
    dict of str to ndarray, shape (k, m)
        Only the unbounded quantities; at most ``LOCATIONS`` points each, in m.
    """
    return singular_extremes(mechanism, grid, names, direct_points=direct_points)[0]
