"""Everything about one pose: joints, Jacobian, conditioning, force polytope and ellipsoids.

``analyse_pose(mechanism, x)`` gathers, for one task point, what the pose view draws and
what ``isoforce pose`` prints. It only calls the batched metric functions (on a batch of
one), so a pose and a map never disagree about a number. SI units throughout; the JSON form
and display units are ``app.logic.pose_report``'s.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Iterable

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.validation import as_points

from . import (
    columns,
    dynamics,
    ellipsoids,
    isotropy,
    linalg,
    parallelepiped,
    wrench_facets,
    wrench_slices,
    wrenches,
    zonotopes,
)
from .bottleneck import BOTTLENECK_SHARED, BOTTLENECK_TIE, tied_actuators
from .ellipsoids import Ellipsoid
from .loading import DEFAULT_LOADING, Loading
from .quantities import QUANTITIES, closure
from .quantity_nodes import add_bias, biased_wrench_slabs


@dataclass(frozen=True, eq=False)
class PoseReport:
    """The force capability of a mechanism at one task point. SI units, radians.

    Attributes
    ----------
    x : ndarray, shape (m,)
        The task point, m.
    reachable : bool
        Inverse kinematics has a solution (in the mechanism's working mode / branch).
    feasible : bool
        Reachable, and inside the joint limits and physical constraints: in the workspace.
    joints : ndarray, shape (n,)
        Actuated joint angles, rad; ``nan`` where unreachable.
    jacobian : ndarray, shape (m, n)
        ``J`` with ``xdot = J qdot``, m/rad.
    singular_values : ndarray, shape (min(m, n),)
        Of ``J``, descending, m/rad.
    condition_number, manipulability : float
        ``sigma_max / sigma_min`` (``inf`` at a singularity) and ``prod sigma`` (SI).
    torque_limits : ndarray, shape (n,)
        Joint-side torque limits ``t_u``, N m.
    facet_distances : ndarray, shape (n,)
        ``t_u / |J[:, u]|``: distance from 0 to each facet pair of the force polytope, N.
    isotropic_force : float
        Their minimum: the maximum isotropic force (paper 000 eq. 8), N.
    bottleneck : int
        The actuator attaining that minimum; ``-1`` where unreachable.
    anisotropic_force : float
        Largest vertex norm of the force polytope (paper 000 eq. 6), N; ``inf`` if singular.
    reference_forces : ndarray, shape (m, n), or None if not requested
        ``J^-T diag(t)``: column u is actuator u's force at full torque, N.
    vertices : ndarray, shape (2^n, m), or None if not requested
        Force polytope vertices, row k for sign vector ``torque_box.sign_patterns(n)[k]``, N.
    faces : list of tuple of int, or None with ``vertices``
        Vertex-index cycles of the parallelepiped's faces (``parallelepiped.parallelepiped_faces``).
    force_ellipsoid : Ellipsoid or None if not requested
        ``{f : |diag(1/t) J^T f| <= 1}``: radii (m,) in N, largest first; axes as columns (m, m).
    velocity_ellipsoid : Ellipsoid or None if not requested
        ``{J qdot : |diag(1/joint_speeds) qdot| <= 1}``: radii (m,) in m/s, axes (m, m).
    joint_speeds : ndarray, shape (n,)
        Joint speed limits the velocity ellipsoid uses, rad/s.
    inertia_ellipsoid : Ellipsoid or None if not requested or the mechanism has no mass model
        Semi-axes along the principal directions of the apparent-mass matrix
        ``((Lambda^-1)_tt)^-1`` (force rows ``t``), each the mass a hand pushing along it feels:
        radii (m or 3,) in kg, largest first, ``inf`` along a direction the handle cannot move in;
        axes (``metrics.dynamics.inertia_ellipsoid``; links and rotors).
    singularity : int or None
        Singularity code (an index into ``singularity_classes``); ``None`` for mechanisms
        without a singularity analysis, ``-1`` where the pose is unreachable.
    singularity_classes : tuple of str
        The mechanism's names of the codes (``Mechanism.singularity_classes``).
    singular_legs : tuple of str
        Actuators whose leg is stretched or folded (inverse singularity); both at a double
        inverse singularity, where J = 0. Empty where none is or the mechanism has no legs.
    joint_names, task_names : tuple of str
        The mechanism's actuator and coordinate names, for labelling.
    task_units, joint_units : tuple of str
        SI unit of each task coordinate (row of J: ``"m"`` or ``"rad"``) and of each actuated
        joint (column: ``"rad"`` revolute, ``"m"`` prismatic legs).
    isotropic_moment, anisotropic_moment : float
        Devices with orientation freedoms (``metrics.wrenches``): the largest ball of moments
        held at zero force and the largest moment at zero force, N m; ``nan`` for the others.
    condition_number_scaling : dict or None
        ``{"length_m": L}`` where the condition number is that of ``diag(1, .., L, ..) J``
        (moments compared with forces over ``L``); ``None`` where it is plain J's.
    loading : Loading
        The torque rating whose limits ``torque_limits`` are, and gravity (``metrics.loading``).
    torque_bias : ndarray, shape (n,)
        Torque the joints spend holding the links (gravity torque), N m; zeros with gravity off.
    force_centre : ndarray, shape (m,)
        Centre of the force set, ``J^-T (hi + lo) / 2`` with ``[lo, hi] = [-t - b, t - b]``, N:
        0 with gravity off; ``nan`` where J is singular, or for sets that are not a
        parallelepiped (orientation freedoms, redundant actuation).

    With gravity on the force polytope is shifted: ``facet_distances`` are signed distances
    ``min(t_u - b_u, t_u + b_u) / |J[:, u]|`` (negative where the origin is outside slab u),
    the isotropic force is the distance from the origin to the nearest facet (0 outside the
    set), the anisotropic force the farthest vertex, ``vertices`` the shifted ones, and
    ``reference_forces`` the half-edges about ``force_centre`` (a bias leaves them as they are).
    The force ellipsoid is the rating's unbiased one, centred at the origin: an ellipsoid
    about 0 cannot stand for a shifted set.

    Devices with orientation freedoms hold wrenches ``(f, m)``; for them ``isotropic_force``
    and ``anisotropic_force`` are those of the forces held at zero moment (N), ``vertices``
    and ``faces`` describe that 3D force set, ``facet_distances`` are its facets' distances
    ``t_u / |J[force rows, u]|`` (square J; ``nan`` when redundant), the force ellipsoid is its
    slice at zero moment ({f : |diag(1/t) J[force rows]^T f| <= 1}) and the velocity
    ellipsoid that of the task point's linear velocity; singular values and manipulability
    are those of the scaled J.
    """

    x: FloatArray
    reachable: bool
    feasible: bool
    joints: FloatArray
    jacobian: FloatArray
    singular_values: FloatArray
    condition_number: float
    manipulability: float
    torque_limits: FloatArray
    facet_distances: FloatArray
    isotropic_force: float
    bottleneck: int
    anisotropic_force: float
    reference_forces: FloatArray | None
    vertices: FloatArray | None
    faces: list[tuple[int, ...]] | None
    force_ellipsoid: Ellipsoid | None
    velocity_ellipsoid: Ellipsoid | None
    joint_speeds: FloatArray
    singularity: int | None
    joint_names: tuple[str, ...]
    task_names: tuple[str, ...]
    #: SI unit of each actuated joint: "rad" (revolute) or "m" (prismatic legs).
    joint_units: tuple[str, ...] = ()
    task_units: tuple[str, ...] = ()
    isotropic_moment: float = float("nan")
    anisotropic_moment: float = float("nan")
    condition_number_scaling: dict | None = None
    singular_legs: tuple[str, ...] = ()
    loading: Loading = DEFAULT_LOADING
    torque_bias: FloatArray | None = None
    force_centre: FloatArray | None = None
    inertia_ellipsoid: Ellipsoid | None = None
    singularity_classes: tuple[str, ...] = ()

    @property
    def bottleneck_name(self) -> str | None:
        """Name of the bottleneck actuator; ``"tie"`` where several limit equally within rounding
        (``bottleneck.BOTTLENECK_TIE``), ``"shared"`` with redundant actuation
        (``bottleneck.BOTTLENECK_SHARED``); ``None`` where unreachable.

        Returns
        -------
        str or None
        """
        if self.bottleneck >= 0:
            return self.joint_names[self.bottleneck]
        return {BOTTLENECK_TIE: "tie", BOTTLENECK_SHARED: "shared"}.get(self.bottleneck)

    @property
    def bottleneck_phrase(self) -> str | None:
        """The bottleneck in words, for captions: ``"theta_0 limits"``; for a tie the actuators
        that tie, ``"theta_1 and theta_2 limit equally"``, or ``"no actuator limits it"`` where
        every facet is at infinity (J = 0); ``"the actuators share the limit"`` with redundant
        actuation; ``None`` where unreachable.

        Returns
        -------
        str or None
        """
        if self.bottleneck >= 0:
            return f"{self.joint_names[self.bottleneck]} limits"
        if self.bottleneck == BOTTLENECK_SHARED:
            return "the actuators share the limit"
        if self.bottleneck != BOTTLENECK_TIE:
            return None
        if np.all(np.asarray(self.facet_distances, float) == np.inf):
            return "no actuator limits it"     # J = 0 (a double inverse singularity): unbounded
        names = [self.joint_names[k] for k in tied_actuators(self.facet_distances)]
        if len(names) < 2:          # (not met: the tie was decided on these distances)
            return "a tie between actuators"
        return f"{', '.join(names[:-1])} and {names[-1]} limit equally"

    @property
    def singularity_name(self) -> str | None:
        """``"none"``, ``"inverse"``, ``"direct"`` or ``"combined"``; ``None`` if not defined.

        Returns
        -------
        str or None
        """
        if self.singularity is None or self.singularity < 0:
            return None
        return self.singularity_classes[self.singularity]

    def clamp(self, desired: ArrayLike) -> FloatArray:
        """A desired force (..., m) in N scaled down to the isotropic radius (paper 000 eq. 9).

        Parameters
        ----------
        desired : array_like, shape (..., m)
            Desired forces ``F_d``, N.

        Returns
        -------
        ndarray, shape (..., m)
            N.
        """
        return isotropy.clamp_force(desired, self.isotropic_force)

    def force_along(self, direction: ArrayLike) -> float:
        """The largest force the actuators hold along ``direction``: max ``s`` with ``s d`` in the
        force set (``d`` the unit vector of ``direction``), N.

        The set is the slabs ``lo_u <= J[:, u] . f <= hi_u`` with ``[lo, hi] = [-t - b, t - b]``
        (``torque_limits`` t, ``torque_bias`` b), on the force rows of a device with orientation
        freedoms (forces at zero moment). What ``clamp`` gives is at most this: the inscribed
        sphere's radius, the same in every direction (paper 000 eq. 9).

        Parameters
        ----------
        direction : array_like, shape (m,)
            Any nonzero vector over the force rows (the task's length coordinates), N or unitless.

        Returns
        -------
        float
            N; ``inf`` where no actuator limits that direction; ``nan`` where no force along it is
            held (the origin outside the set, gravity beyond the rating, and the ray missing the
            set), unreachable, with redundant actuation (the set is a zonotope, not slabs) or for
            a zero direction.
        """
        d = np.asarray(direction, float)
        norm = float(np.linalg.norm(d))
        jac = np.asarray(self.jacobian, float)
        if not self.reachable or norm == 0.0 or not np.isfinite(norm) or jac.shape[0] != jac.shape[1]:
            return float("nan")
        rows = [k for k, unit in enumerate(self.task_units or ("m",) * jac.shape[0]) if unit == "m"]
        c = jac[rows].T @ (d / norm)                 # J[:, u] . d for each actuator u
        t = np.asarray(self.torque_limits, float)
        b = np.zeros_like(t) if self.torque_bias is None else np.asarray(self.torque_bias, float)
        lo, hi = -t - b, t - b
        # Along the ray s d (s >= 0) slab u holds s in [lo/c, hi/c] (c > 0), [hi/c, lo/c] (c < 0),
        # every s or none (c = 0, as 0 is in [lo, hi] or not); the set's s are their intersection.
        with np.errstate(divide="ignore", invalid="ignore"):
            upper = np.where(c > 0, hi / c, np.where(c < 0, lo / c, np.inf))
            lower = np.where(c > 0, lo / c, np.where(c < 0, hi / c, -np.inf))
        if np.any((c == 0) & ((lo > 0) | (hi < 0))) or max(0.0, float(np.max(lower))) > float(np.min(upper)):
            return float("nan")
        return float(np.min(upper))


#: The parts of a report that are computed only on request (the scalars always are).
OPTIONAL_PARTS = ("vertices", "reference_forces", "force_ellipsoid", "velocity_ellipsoid", "inertia_ellipsoid")


def analyse_pose(mechanism, x: ArrayLike, *, joint_speeds: ArrayLike | None = None,
                 parts: Iterable[str] | None = None, loading: Loading | None = None) -> PoseReport:
    """Analyse one task point ``x`` (m,) in m.

    Parameters
    ----------
    mechanism : kinematics.Mechanism
        A model with a square Jacobian (n = m).
    x : array_like, shape (m,)
        The task point, m.
    joint_speeds : array_like, shape (n,), optional
        Joint speed limits for the velocity ellipsoid, rad/s; default 1 rad/s each, so the
        ellipsoid is the image of the unit ball of joint rates.
    parts : iterable of str, optional
        Which of ``OPTIONAL_PARTS`` to compute; default all. A part left out is ``None`` in
        the report (a view that hides the polytope does not pay for it). The scalars
        (condition number, isotropic and anisotropic force, bottleneck, ...) always come.
        ``inertia_ellipsoid`` needs a mass model (``mechanism.has_mass_model``): ``None``
        without one, asked for or not.
    loading : Loading, optional
        Torque rating and gravity (``metrics.loading``); default continuous, gravity off.

    Returns
    -------
    PoseReport
        Reachable but infeasible points (outside joint limits or the body constraint) get
        every number, with ``feasible = False``; unreachable points get ``nan`` (``-1``
        for the bottleneck), never an exception.

    Raises
    ------
    ValueError
        For a bad ``x``, ``joint_speeds`` or ``parts``, or a ``loading`` the mechanism cannot
        take (``Loading.check``).
    """
    m, n = mechanism.task_dim, mechanism.n_joints
    point = as_points("x", x, m)
    if point.shape != (m,):
        raise ValueError(f"x must be one point of shape ({m},), got {point.shape}")
    if n < m:
        raise ValueError(f"analyse_pose needs at least as many actuators as task coordinates, got n = {n}, m = {m}")
    speeds = ellipsoids.actuator_limits(
        "joint_speeds", np.ones(n) if joint_speeds is None else joint_speeds, n)
    wanted = _check_parts(parts)
    if not mechanism.has_mass_model:
        wanted = wanted - {"inertia_ellipsoid"}
    loading = DEFAULT_LOADING if loading is None else loading
    loading.check(mechanism)
    # A batch of one all the way through: the metric functions are written for batches.
    batch = point[None, :]
    q, reachable = mechanism.inverse(batch)
    reachable_1 = bool(reachable[0])
    feasible_1 = reachable_1 and bool(mechanism.feasible(q, batch)[0])
    torques = loading.torque_set(mechanism)      # validated once; every metric below takes it as it is
    common = dict(x=point, reachable=reachable_1, feasible=feasible_1, torque_limits=torques.limits, loading=loading,
                  joint_speeds=np.asarray(speeds, float),
                  faces=_parallelepiped_faces(n) if "vertices" in wanted and n == m <= 3 else None,
                  joint_names=tuple(mechanism.joint_names), task_names=tuple(mechanism.task_names),
                  joint_units=tuple(mechanism.joint_units),
                  task_units=tuple(mechanism.task_units),
                  singularity_classes=tuple(mechanism.singularity_classes),
                  condition_number_scaling=wrenches.condition_number_scaling(mechanism))
    if not reachable_1:
        return _frozen(_unreachable(m, n, mechanism, common, wanted))

    # The quantity graph's own nodes: the same Jacobian (a five-bar gets its pose, as in a
    # map) and, for redundant actuation, the same zonotope as a map uses.
    values: dict = {"joints": q, "pose": batch, "loading": loading, "torques": torques}
    wrench = mechanism.has_orientation
    scalars = POSE_SCALARS + (("isotropic_moment", "anisotropic_moment") if wrench else ())
    # The mass matrices only for the inertia ellipsoid: a view that hides it does not pay for M.
    scalars += ("mass_matrices",) if "inertia_ellipsoid" in wanted else ()
    for name in closure(scalars, mechanism, loading):
        values[name] = QUANTITIES[name].run(values, mechanism)
        if name == "torque_bias":
            add_bias(values)
    jac, ref = values["jacobian"], values["reference_forces"]
    square = not mechanism.is_redundant
    torques = values["torques"]
    bias = torques.bias                                          # (1, n) or None: the symmetric code
    centre = np.zeros(m) if bias is None else np.full(m, np.nan)
    if wrench:
        # Forces at zero moment: a 3D polytope, the ellipsoids' force / linear-velocity parts.
        rows = list(wrenches.force_rows(mechanism))
        sv = linalg.singular_values(jac * wrenches.task_row_scale(mechanism)[:, None])
        values["singular_values"], values["manipulability"] = sv, np.prod(sv, axis=-1)
        if "vertices" not in wanted:
            vertices = None
        elif bias is None:
            vertices = wrench_slices.slice_vertices(ref[0], rows=rows)
        else:       # gravity on: the slice of the shifted set, from its slabs
            nu, lo, hi = biased_wrench_slabs(values, mechanism)
            vertices = wrench_facets.slab_slice_vertices(nu[0], lo[0], hi[0], rows=rows)
        common["faces"] = wrench_slices.hull_faces(vertices) if vertices is not None else None
        # Each slab's nearer face, as isotropic_force.
        facets = (wrench_facets.slice_facet_distances(jac, torque_limits=torques.nearer, rows=rows)[0] if square
                  else np.full(n, np.nan))
        ellipsoid_jac = jac[..., rows, :]
    else:
        ellipsoid_jac = jac
        if "vertices" not in wanted:
            vertices = None
        elif square:
            vertices = _parallelepiped_vertices(jac, ref, torques)
        else:
            vertices = zonotopes.zonotope_vertices(ref, torque_limits=torques.per_unit)[0]
        facets = (isotropy.facet_distances(norms=columns.column_norms(jac), torque_limits=torques)[0] if square
                  else np.full(n, np.nan))
        if bias is not None and square:
            centre = parallelepiped.polytope_centre(jac, torque_limits=torques)[0]
    singularity = int(mechanism.singularity(q, batch)[0]) if mechanism.singularity_classes else None
    legs = mechanism.singular_legs(q, batch)[0]
    return _frozen(PoseReport(
        joints=q[0],
        jacobian=jac[0],
        singular_values=values["singular_values"][0],
        condition_number=float(values["condition_number"][0]),
        manipulability=float(values["manipulability"][0]),
        facet_distances=facets,
        isotropic_force=float(values["isotropic_force"][0]),
        bottleneck=int(values["bottleneck"][0]),
        anisotropic_force=float(values["anisotropic_force"][0]),
        reference_forces=ref[0] if "reference_forces" in wanted else None,
        vertices=vertices,
        force_ellipsoid=(_first(ellipsoids.force_ellipsoid(ellipsoid_jac, torque_limits=torques))
                         if "force_ellipsoid" in wanted else None),
        velocity_ellipsoid=(_first(ellipsoids.velocity_ellipsoid(ellipsoid_jac, joint_speed_limits=speeds))
                            if "velocity_ellipsoid" in wanted else None),
        inertia_ellipsoid=(_first(dynamics.inertia_ellipsoid(values["mass_matrices"][:, 1],
                                                             wrenches.force_rows(mechanism)))
                           if "inertia_ellipsoid" in wanted else None),
        singularity=singularity,
        singular_legs=tuple(name for name, leg in zip(mechanism.joint_names, legs) if leg),
        isotropic_moment=float(values["isotropic_moment"][0]) if wrench else float("nan"),
        anisotropic_moment=float(values["anisotropic_moment"][0]) if wrench else float("nan"),
        torque_bias=np.zeros(n) if bias is None else bias[0],
        force_centre=centre,
        **common,
    ))


#: What every report holds, computed through the quantity graph.
POSE_SCALARS = ("condition_number", "manipulability", "isotropic_force", "bottleneck", "anisotropic_force",
                "reference_forces")


def _check_parts(parts: Iterable[str] | None) -> frozenset[str]:
    """The requested optional parts (all by default), or a ValueError naming ``parts``."""
    if parts is None:
        return frozenset(OPTIONAL_PARTS)
    if isinstance(parts, str):
        raise ValueError(f"parts must be a collection of names, got the string {parts!r}")
    wanted = frozenset(parts)
    unknown = sorted(wanted - set(OPTIONAL_PARTS))
    if unknown:
        raise ValueError(f"parts has unknown name {unknown[0]!r}; choose from {', '.join(OPTIONAL_PARTS)}")
    return wanted


def _first(ellipsoid: Ellipsoid) -> Ellipsoid:
    """The single ellipsoid of a batch of one."""
    return Ellipsoid(radii=ellipsoid.radii[0], axes=ellipsoid.axes[0])


def _unreachable(m: int, n: int, mechanism, common: dict, wanted: frozenset[str]) -> PoseReport:
    """The report of a point IK cannot reach: shapes as usual, every number ``nan``."""
    nan = float("nan")
    r = len(wrenches.force_rows(mechanism))

    def part(name, make):
        return make() if name in wanted else None

    return PoseReport(
        joints=np.full(n, nan), jacobian=np.full((m, n), nan), singular_values=np.full(min(m, n), nan),
        condition_number=nan, manipulability=nan, facet_distances=np.full(n, nan), isotropic_force=nan,
        bottleneck=-1, anisotropic_force=nan,
        reference_forces=part("reference_forces", lambda: np.full((m, n), nan)),
        vertices=part("vertices", lambda: np.full((2 ** n, m), nan)),
        force_ellipsoid=part("force_ellipsoid", lambda: Ellipsoid(np.full(m, nan), np.full((m, m), nan))),
        velocity_ellipsoid=part("velocity_ellipsoid", lambda: Ellipsoid(np.full(m, nan), np.full((m, m), nan))),
        inertia_ellipsoid=part("inertia_ellipsoid", lambda: Ellipsoid(np.full(r, nan), np.full((r, r), nan))),
        singularity=-1 if mechanism.singularity_classes else None,
        torque_bias=np.full(n, nan), force_centre=np.full(m, nan),
        **common,
    )


def _parallelepiped_faces(n: int) -> list[tuple[int, ...]]:
    """``parallelepiped.parallelepiped_faces(n)``: a new list of the same cycles, made once per ``n``
    (a slider step analyses a pose: the cycles took ~0.1 ms to list)."""
    return list(_faces_of(n))


@functools.lru_cache(maxsize=None)
def _faces_of(n: int) -> tuple[tuple[int, ...], ...]:
    return tuple(parallelepiped.parallelepiped_faces(n))


def _parallelepiped_vertices(jac: np.ndarray, ref: np.ndarray, torques) -> np.ndarray:
    """``parallelepiped.polytope_vertices(jac, torque_limits=torques)[0]``, (2^n, m), from the
    reference forces ``ref`` (1, n, n) the quantity graph made: with no bias, the same ``R`` that
    function makes (``reference_forces`` of the same set), so the same vertices ``R s``, bit for
    bit, without computing ``J^-T`` again; a shifted set takes its own path there."""
    if torques.bias is None and torques.centred_limits is not None:
        return np.einsum("...ij,kj->...ki", ref, parallelepiped.sign_patterns(ref.shape[-1]))[0]
    return parallelepiped.polytope_vertices(jac, torque_limits=torques)[0]


def _frozen(report: PoseReport) -> PoseReport:
    """Make the report's arrays read-only, so a frozen report is immutable all the way down."""
    for value in vars(report).values():     # None parts are skipped: not arrays
        arrays = (value.radii, value.axes) if isinstance(value, Ellipsoid) else (value,)
        for arr in arrays:
            if isinstance(arr, np.ndarray):
                arr.setflags(write=False)
    return report
