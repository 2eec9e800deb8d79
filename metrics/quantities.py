"""The quantity dependency graph: a request names what it needs, and only that is computed.

::

    pose -> joints -> jacobian -> singular_values -> condition_number, manipulability
                   -> torque_bias (gravity on: the torque the joints spend holding the links)
    (devices with orientation freedoms, metrics.wrenches: jacobian -> condition_number scaled
     by the characteristic length; force map -> reference_forces -> wrench_facets ->
     isotropic_force / _moment at zero moment / force; reference_forces -> anisotropic_*)
                               -> column_norms    -> isotropic_force, bottleneck
                               -> reference_forces -> anisotropic_force
                               -> force_ellipsoid_min_radius
                   -> singularity (five-bar)

``evaluate`` inverts the kinematics, masks infeasible points, and computes the closure of
the requested quantities at the feasible points only. Infeasible points get ``nan``
(``-1`` for integer quantities).

A ``loading=`` (``metrics.loading.Loading``) picks the rated torque limits ``t`` (continuous
or peak) for every force node, and with gravity on adds ``torque_bias`` to the inputs of the
nodes whose force set it shifts (``BIASED_NODES``): their set is
``{f : -t - b <= J^T f <= t - b}`` (``torque_box.torque_range``). The force ellipsoid stays
the unbiased ``{f : |diag(1/t) J^T f| <= 1}`` of the rating: an ellipsoid about the origin
cannot describe a shifted set, so with gravity on it is the set's shape, not its position.
The reference forces are the half-edges of the shifted parallelepiped, which a bias leaves
unchanged (its centre moves, ``parallelepiped.polytope_centre``). ``loading=None`` is
``Loading()``: continuous rating, gravity off, the same numbers bit for bit.

Singular poses need no node of their own: where a mechanism classes a pose singular (the
five-bar's ``singularity``), its ``jacobian`` is the exact singular J (zero columns for
stretched or folded legs, ``inf`` at a direct singularity), so every node downstream takes
its singular limit (condition number, isotropic and anisotropic force ``inf`` at a double
inverse singularity), and a map and a pose, which share the ``jacobian`` node, agree.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.registry import MECHANISMS

from . import (
    bottleneck,
    columns,
    conditioning,
    dynamics,
    ellipsoids,
    isotropy,
    kernels,
    linalg,
    parallelepiped,
    resolution,
    wrench_facets,
    wrenches,
    zonotopes,
)
from . import quantity_nodes as nodes
from .loading import DEFAULT_LOADING, Loading


@dataclass(frozen=True)
class Quantity:
    """One node: its inputs, unit, one-sentence definition, and how to compute it."""

    name: str
    needs: tuple[str, ...]
    unit: str
    label: str
    description: str
    compute: Callable[[dict[str, Any], Any], Any]
    scalar: bool = True          # a per-point scalar that a map can show
    categorical: bool = False    # integer classes: no mean or SD
    #: Inputs and computation for redundantly actuated mechanisms (``mech.is_redundant``),
    #: whose force set is the zonotope ``A [-t, t]^n`` of their force map, not J's polytope.
    redundant_needs: tuple[str, ...] | None = None
    redundant_compute: Callable[[dict[str, Any], Any], Any] | None = None
    #: Inputs and computation for mechanisms with orientation freedoms
    #: (``Mechanism.has_orientation``): forces at zero moment, moments at zero force, a
    #: task-scaled condition number (``metrics.wrenches``). Takes precedence over ``redundant_*``.
    wrench_needs: tuple[str, ...] | None = None
    wrench_compute: Callable[[dict[str, Any], Any], Any] | None = None
    #: Only for mechanisms with orientation freedoms (the moment capabilities).
    wrench_only: bool = False
    #: Only for mechanisms whose joint sensors are modelled (a ``joint_resolution`` parameter).
    sensed_only: bool = False
    #: Only for mechanisms with a mass model (``Mechanism.has_mass_model``): masses, accelerations, weight.
    massed_only: bool = False
    #: Only for mechanisms whose motor speeds are given (``Mechanism.joint_speed_limits`` not None).
    speed_only: bool = False

    def inputs(self, mech) -> tuple[str, ...]:
        """The names this node needs for ``mech``: ``wrench_needs``, ``redundant_needs`` or ``needs``.

        Parameters
        ----------
        mech : Mechanism
            The model the graph is evaluated for.

        Returns
        -------
        tuple of str

        Examples
        --------
        >>> from kinematics.fivebar import FiveBar
        >>> QUANTITIES["condition_number"].inputs(FiveBar())
        ('singular_values',)
        """
        if self.wrench_needs is not None and mech.has_orientation:
            return self.wrench_needs
        return self.redundant_needs if self.redundant_needs is not None and mech.is_redundant else self.needs

    def run(self, values: dict[str, Any], mech) -> Any:
        """Compute this node from the values of its inputs, with the variant ``inputs`` chose.

        Parameters
        ----------
        values : dict of str to ndarray
            Every input of ``inputs(mech)`` (and ``"pose"`` (k, m), ``"joints"`` (k, n)), batch (k,).
        mech : Mechanism
            The model.

        Returns
        -------
        ndarray
            Batch shape (k,) first, e.g. (k,) for a scalar, (k, m, n) for the Jacobian.
        """
        if self.wrench_compute is not None and mech.has_orientation:
            return self.wrench_compute(values, mech)
        if self.redundant_compute is not None and mech.is_redundant:
            return self.redundant_compute(values, mech)
        return self.compute(values, mech)


_NODES = [
    Quantity("jacobian", ("joints", "pose"), "m/rad", "Jacobian", "J with xdot = J qdot.",
             nodes.jacobian_at_pose, scalar=False),
    Quantity("singular_values", ("jacobian",), "m/rad", "Singular values", "Singular values of J, descending.",
             lambda v, m: linalg.singular_values(v["jacobian"]), scalar=False),
    Quantity("condition_number", ("singular_values",), "", "Condition number",
             "Ratio of J's largest to smallest singular value: 1 is isotropic, inf singular.",
             lambda v, m: conditioning.condition_number(sv=v["singular_values"]),
             # Rows mixing m/s and rad/s: rotational rows scaled by the device's characteristic length.
             wrench_needs=("jacobian",), wrench_compute=nodes.scaled_condition),
    Quantity("inverse_condition_number", ("condition_number",), "", "Inverse condition number",
             "1 / condition number, 0 singular and 1 isotropic, whose workspace mean is the global "
             "conditioning index (Gosselin and Angeles 1991).",
             lambda v, m: 1.0 / v["condition_number"]),
    Quantity("manipulability", ("singular_values",), "", "Yoshikawa manipulability",
             "sqrt(det(J J^T)): the volume of the velocity ellipsoid for unit joint rates (SI units of J).",
             lambda v, m: conditioning.manipulability(sv=v["singular_values"])),
    Quantity("column_norms", ("jacobian",), "m/rad", "Column norms", "Norm of each column of J.",
             lambda v, m: columns.column_norms(v["jacobian"]), scalar=False),
    Quantity("isotropic_force", ("column_norms",), "N", "Max. isotropic force",
             "Largest force the device can exert in every direction at this pose (paper 000 eq. 8).",
             lambda v, m: isotropy.isotropic_force(norms=v["column_norms"], torque_limits=nodes.torques_of(v, m)),
             redundant_needs=("reference_forces",),
             redundant_compute=lambda v, m: zonotopes.zonotope(
                 v["reference_forces"], torque_limits=nodes.torques_of(v, m).per_unit).inscribed_radius,
             # Orientation freedoms: the largest ball of forces held at zero moment (N).
             wrench_needs=("wrench_facets",),
             wrench_compute=lambda v, m: nodes.wrench_radius(v, m, wrenches.force_rows(m))),
    Quantity("bottleneck", ("column_norms",), "", "Bottleneck actuator",
             "The actuator whose torque limit caps the isotropic force here.",
             lambda v, m: bottleneck.bottleneck_actuator(norms=v["column_norms"],
                                                        torque_limits=nodes.torques_of(v, m)),
             categorical=True,
             # With redundant actuation no single actuator caps the isotropic force: shared.
             redundant_needs=("joints",),
             redundant_compute=lambda v, m: np.full(len(v["joints"]), bottleneck.BOTTLENECK_SHARED),
             # Orientation freedoms: the actuator whose facet of the zero-moment force set is nearest.
             wrench_needs=("joints", "jacobian"),
             wrench_compute=lambda v, m: nodes.wrench_bottleneck(v, m)),
    Quantity("reference_forces", ("jacobian",), "N", "Reference forces",
             "Columns of J^-T diag(t): the force of each actuator at full torque.",
             lambda v, m: parallelepiped.reference_forces(v["jacobian"],
                                                          torque_limits=nodes.torques_of(v, m).unbiased),
             scalar=False,
             redundant_needs=("joints", "pose"), redundant_compute=nodes.generators,
             # Orientation freedoms: the force map's columns (finite where J = K^-1 is not).
             wrench_needs=("joints", "pose"), wrench_compute=nodes.generators),
    Quantity("anisotropic_force", ("reference_forces", "jacobian"), "N", "Max. anisotropic force",
             "Largest force the device can exert in its best direction here: the longest polytope vertex.",
             nodes.anisotropic,
             redundant_needs=("reference_forces",),
             redundant_compute=nodes.redundant_anisotropic,
             # Orientation freedoms: the largest force held at zero moment (N).
             wrench_needs=("reference_forces", "jacobian"),
             wrench_compute=lambda v, m: nodes.wrench_slice_max(v, m, wrenches.force_rows(m))),
    Quantity("wrench_facets", ("jacobian",), "", "Wrench-set facets",
             "Slabs |nu . w| <= h bounding the wrench set: normals (k, m) then offsets, packed (k, m + 1).",
             lambda v, m: nodes.square_facets(v["jacobian"], nodes.rated_limits(v, m)), scalar=False, wrench_only=True,
             redundant_needs=("reference_forces",),
             redundant_compute=lambda v, m: wrench_facets.packed_facets(nodes.contiguous_generators(v))),
    Quantity("isotropic_moment", ("wrench_facets",), "N m", "Max. isotropic moment",
             "Largest moment the device can exert about every axis while exerting no force.",
             lambda v, m: nodes.wrench_radius(v, m, wrenches.moment_rows(m)), wrench_only=True),
    Quantity("anisotropic_moment", ("reference_forces", "jacobian"), "N m", "Max. anisotropic moment",
             "Largest moment the device can exert about its best axis while exerting no force.",
             lambda v, m: nodes.wrench_slice_max(v, m, wrenches.moment_rows(m)),
             wrench_only=True),
    Quantity("force_ellipsoid_min_radius", ("jacobian",), "N", "Min. force-ellipsoid radius",
             "Smallest semi-axis of the force ellipsoid {f : |diag(1/t) J^T f| <= 1}.",
             lambda v, m: ellipsoids.force_ellipsoid_min_radius(v["jacobian"], torque_limits=nodes.torques_of(v, m)),
             # Orientation freedoms: the ellipsoid's slice at zero moment, {f : |diag(1/t) J[f, :]^T f| <= 1}.
             wrench_needs=("jacobian",), wrench_compute=lambda v, m: ellipsoids.force_ellipsoid_min_radius(
                 v["jacobian"][..., list(wrenches.force_rows(m)), :], torque_limits=nodes.torques_of(v, m))),
    Quantity("torque_bias", ("joints",), "N m", "Gravity torque",
             "Torque each joint spends holding the links against gravity at this pose (0 with gravity off).",
             nodes.torque_bias, scalar=False,
             wrench_needs=("joints", "jacobian"), wrench_compute=nodes.gravity_torque_at_pose),
    Quantity("axis_resolution", ("jacobian",), "m", "Resolution per task axis",
             "Largest move along each task axis from one sensor count on one joint, max_u |J[i, u]| delta_u "
             "(m, rad for a rotation axis).",
             lambda v, m: resolution.axis_resolution(v["jacobian"], resolution.mechanism_steps(m)),
             scalar=False, sensed_only=True),
    Quantity("spatial_resolution", ("jacobian",), "m", "Spatial resolution",
             "Largest end-effector move from one sensor count on one joint, max_u |J[:, u]| delta_u "
             "(position rows only for a pen or platform).",
             lambda v, m: resolution.spatial_resolution(v["jacobian"], resolution.mechanism_steps(m),
                                                        rows=wrenches.force_rows(m)),
             sensed_only=True),
    Quantity("angular_resolution", ("jacobian",), "rad", "Angular resolution",
             "Largest end-effector turn from one sensor count on one joint (rotation rows of J).",
             lambda v, m: resolution.spatial_resolution(v["jacobian"], resolution.mechanism_steps(m),
                                                        rows=wrenches.moment_rows(m)),
             wrench_only=True, sensed_only=True),
    Quantity("mass_matrices", ("joints", "pose", "jacobian"), "kg", "Task-space inertia and mobility",
             "Lambda = (J M^-1 J^T)^-1 and its inverse, packed (k, 2, m, m).",
             nodes.inertias, scalar=False, massed_only=True),
    Quantity("apparent_mass_range", ("mass_matrices",), "kg", "Apparent-mass range",
             "Lightest and heaviest apparent mass of a pure force over directions (k, 2).",
             nodes.mass_range, scalar=False, massed_only=True),
    Quantity("apparent_mass_min", ("apparent_mass_range",), "kg", "Min. apparent mass",
             "Smallest mass a hand feels pushing (a pure force) in any direction: 1 / the largest "
             "eigenvalue of J M^-1 J^T (translational block).",
             lambda v, m: v["apparent_mass_range"][:, 0], massed_only=True),
    Quantity("apparent_mass_max", ("apparent_mass_range",), "kg", "Max. apparent mass",
             "Largest mass a hand feels pushing (a pure force) in any direction; inf where it cannot move.",
             lambda v, m: v["apparent_mass_range"][:, 1], massed_only=True),
    Quantity("mass_condition_number", ("apparent_mass_range",), "", "Mass condition number",
             "Largest over smallest apparent mass: 1 is dynamically isotropic.",
             lambda v, m: np.where(nodes.singular_marked(v), np.inf,
                                   v["apparent_mass_range"][:, 1] / v["apparent_mass_range"][:, 0]),
             massed_only=True),
    Quantity("isotropic_acceleration", ("jacobian", "mass_matrices"), "m/s^2", "Max. isotropic acceleration",
             "Largest acceleration the actuators give the handle in every direction (the acceleration "
             "polytope's inscribed ball; links and rotors, no load).",
             lambda v, m: dynamics.isotropic_acceleration(v["jacobian"], v["mass_matrices"][:, 0],
                                                          torque_limits=nodes.torques_of(v, m)),
             massed_only=True,
             redundant_needs=("reference_forces", "mass_matrices"),
             redundant_compute=lambda v, m: nodes.acceleration_slabs(v, m, wrench_facets.packed_facets(
                 v["reference_forces"])),
             wrench_needs=("wrench_facets", "mass_matrices"),
             wrench_compute=lambda v, m: nodes.acceleration_slabs(v, m, v["wrench_facets"])),
    Quantity("isotropic_velocity", ("jacobian",), "m/s", "Max. isotropic velocity",
             "Largest speed the motors give the handle in every direction (the velocity polytope's inscribed "
             "ball; joint speeds = motor speeds / gear ratios; at zero angular velocity for a pen or platform).",
             nodes.velocity_radius, speed_only=True,
             redundant_needs=("joints", "pose"), redundant_compute=nodes.velocity_radius,
             wrench_needs=("joints", "pose"), wrench_compute=nodes.velocity_radius),
    Quantity("peak_velocity", ("joints", "pose"), "m/s", "Peak velocity per task axis",
             "Fastest pure motion along each task axis, min_u qdot_max_u / |K[u, i]| (m/s, rad/s for a "
             "rotation axis), (k, m).",
             nodes.peak_velocity, scalar=False, speed_only=True),
    Quantity("weight", ("joints", "pose"), "N", "Weight at the handle",
             "Force the hand holds to keep the handle still against gravity (the loading's mounting, "
             "upright when gravity is off).",
             nodes.weight, massed_only=True),
    Quantity("singularity", ("joints", "pose"), "", "Singularity class",
             "0 none, 1 inverse (boundary), 2 direct, 3 combined (paper 002 sec. 3.4).",
             lambda v, m: m.singularity(v["joints"], v["pose"]), categorical=True),
]
QUANTITIES: dict[str, Quantity] = {q.name: q for q in _NODES}
#: Nodes whose force set a torque bias shifts: with gravity on they need ``torque_bias`` too.
#: (``reference_forces``, the half-edges, and the force ellipsoid do not move with a bias.)
BIASED_NODES = frozenset({"isotropic_force", "bottleneck", "anisotropic_force", "isotropic_acceleration",
                          "isotropic_moment", "anisotropic_moment"})
#: Per-point scalar quantities a map can show.
MAP_QUANTITIES = tuple(q.name for q in _NODES if q.scalar)
#: The device's core quantities: condition number, maximum anisotropic and maximum isotropic
#: force (the figures Łącki, Rossa and Gallacher tabulate; docs/references.md).
CORE_QUANTITIES = ("condition_number", "anisotropic_force", "isotropic_force")
#: What every statistics report carries (``isoforce stats``, the app's panel, convergence):
#: the core quantities, and 1 / condition number, whose workspace mean is the GCI.
STATS_QUANTITIES = CORE_QUANTITIES + ("inverse_condition_number",)


def available_quantities(mechanism) -> tuple[str, ...]:
    """Map quantities this mechanism supports (``singularity`` only where it is defined, the
    moment capabilities only for mechanisms with orientation freedoms).

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    tuple of str
        Names from ``MAP_QUANTITIES``, in their order.

    Examples
    --------
    >>> from kinematics.inverse3 import Inverse3
    >>> "singularity" in available_quantities(Inverse3())
    False
    """
    return tuple(q for q in MAP_QUANTITIES if (q != "singularity" or nodes.needs_singularity(mechanism))
                 and _applies(QUANTITIES[q], mechanism))


def _applies(node: Quantity, mechanism) -> bool:
    return ((not node.wrench_only or mechanism.has_orientation)
            and (not node.sensed_only or resolution.mechanism_steps(mechanism) is not None)
            and (not node.massed_only or mechanism.has_mass_model)
            and (not node.speed_only or mechanism.joint_speed_limits() is not None))


#: What a statistics report adds for a device with a mass model: the force bought and the mass paid.
DYNAMIC_SUMMARY = ("apparent_mass_min", "apparent_mass_max", "isotropic_acceleration")
#: What a statistics report adds for a device whose motor speeds are given.
SPEED_SUMMARY = ("isotropic_velocity",)


def summary_quantities(mechanism) -> tuple[str, ...]:
    """``STATS_QUANTITIES``, the moment capabilities of a mechanism with orientation freedoms, the
    spatial (and angular) resolution of one whose joint sensors are modelled, the apparent
    masses and isotropic acceleration of one with a mass model (``DYNAMIC_SUMMARY``), and the
    isotropic velocity of one whose motor speeds are given (``SPEED_SUMMARY``).

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> summary_quantities(FiveBar())
    ('condition_number', 'anisotropic_force', 'isotropic_force', 'inverse_condition_number')
    """
    extra = ("isotropic_moment", "anisotropic_moment") if mechanism.has_orientation else ()
    sensed = tuple(q for q in ("spatial_resolution", "angular_resolution") if _applies(QUANTITIES[q], mechanism))
    dynamic = DYNAMIC_SUMMARY if mechanism.has_mass_model else ()
    speed = SPEED_SUMMARY if mechanism.joint_speed_limits() is not None else ()
    return STATS_QUANTITIES + extra + sensed + dynamic + speed


def check_quantities(mechanism, names) -> tuple[str, ...]:
    """Validate requested quantity names for ``mechanism``; raise naming the bad one.

    Parameters
    ----------
    mechanism : Mechanism
        Any model.
    names : iterable of str
        Requested quantity names (any of ``QUANTITIES`` that apply to ``mechanism``).

    Returns
    -------
    tuple of str
        ``names``, in order.

    Raises
    ------
    ValueError
        Naming the first unknown or inapplicable name and the choices.
    """
    names = tuple(names)
    known = set(QUANTITIES) if nodes.needs_singularity(mechanism) else set(QUANTITIES) - {"singularity"}
    known = {name for name in known if _applies(QUANTITIES[name], mechanism)}
    for name in names:
        if name in QUANTITIES and QUANTITIES[name].massed_only and not mechanism.has_mass_model:
            raise ValueError(f"quantity {name!r} needs a mass model (bodies' masses and inertias), and this "
                             f"{type(mechanism).__name__} has none")
        if name in QUANTITIES and QUANTITIES[name].speed_only and mechanism.joint_speed_limits() is None:
            raise ValueError(f"quantity {name!r} needs the motors' speeds: {nodes.no_speeds(mechanism)}")
        if name not in known:
            raise ValueError(f"unknown quantity {name!r} for {type(mechanism).__name__}; "
                             f"choose from {', '.join(available_quantities(mechanism))}")
    return names


def closure(names, mechanism=None, loading: Loading | None = None) -> list[str]:
    """The requested nodes and everything they need, in an order that computes inputs first.

    The inputs of a few nodes depend on the mechanism (redundant actuation); without one,
    the non-redundant graph is used. With a ``loading`` whose gravity is on, the
    ``BIASED_NODES`` also need ``torque_bias``.

    Parameters
    ----------
    names : iterable of str
        Requested quantity names.
    mechanism : Mechanism, optional
        The model whose variant of the graph to use.
    loading : Loading, optional
        The rating and gravity (``metrics.loading``); default continuous, gravity off.

    Returns
    -------
    list of str
        Node names, inputs before the nodes that need them (``"pose"`` and ``"joints"`` left out).

    Examples
    --------
    >>> closure(["condition_number"])
    ['jacobian', 'singular_values', 'condition_number']
    >>> closure(["isotropic_force"], loading=Loading(gravity=(0.0, 0.0, -9.81)))
    ['jacobian', 'column_norms', 'torque_bias', 'isotropic_force']
    """
    order: list[str] = []
    biased = loading is not None and loading.biased

    def visit(name: str) -> None:
        if name in order or name in ("pose", "joints"):
            return
        node = QUANTITIES[name]
        deps = node.inputs(mechanism) if mechanism is not None else node.needs
        if biased and name in BIASED_NODES:
            deps = tuple(deps) + ("torque_bias",)
        for dep in deps:
            visit(dep)
        order.append(name)

    for name in names:
        visit(name)
    return order


@dataclass
class Evaluation:
    """Result of ``evaluate``: the feasible mask (...), joints (..., n), and each quantity (...)."""

    feasible: np.ndarray
    joints: FloatArray
    values: dict[str, np.ndarray]
    computed: tuple[str, ...] = field(default=())   # every node touched, for tests and logs


def evaluate(mechanism, points: ArrayLike, quantities, *, loading: Loading | None = None) -> Evaluation:
    """Compute ``quantities`` at task-space ``points`` (..., m) in m; only at feasible points.

    Every requested name comes back with the points' batch shape; extra nodes needed on the
    way are not returned (``computed`` lists them).

    Parameters
    ----------
    mechanism : Mechanism
        The model.
    points : array_like, shape (..., m)
        Task points, m (and rad for orientation coordinates).
    quantities : iterable of str
        Names to compute (``check_quantities``).
    loading : Loading, optional
        Torque rating and gravity (``metrics.loading``); default continuous, gravity off.

    Returns
    -------
    Evaluation
        ``feasible`` (...), ``joints`` (..., n) and ``values[name]`` (...) (non-scalar nodes
        with their own trailing axes); ``nan`` (``-1`` for categorical ones) at infeasible points.

    Raises
    ------
    ValueError
        For an unknown quantity, ``points`` of the wrong shape, or a ``loading`` the mechanism
        cannot take (``Loading.check``: no peak rating, no mass model).

    Examples
    --------
    >>> from kinematics.fivebar import FiveBar
    >>> result = evaluate(FiveBar(), [[0.0, 0.2], [0.0, 1.0]], ["isotropic_force", "bottleneck"])
    >>> result.feasible.tolist(), int(result.values["bottleneck"][1])
    ([True, False], -1)
    """
    names = check_quantities(mechanism, quantities)
    loading = DEFAULT_LOADING if loading is None else loading
    loading.check(mechanism)
    x = np.asarray(points, dtype=np.float64)
    if x.ndim == 0 or x.shape[-1] != mechanism.task_dim:
        raise ValueError(f"points must have shape (..., {mechanism.task_dim}), got {x.shape}")
    fused = compiled_kernel(mechanism, names, loading)
    if fused is not None:          # one compiled pass for this family and request (metrics.kernels)
        return compiled_evaluate(fused, x, names, loading)
    batch = x.shape[:-1]
    flat = x.reshape(-1, mechanism.task_dim)
    q, reachable = mechanism.inverse(flat)
    feasible = reachable.copy()
    feasible[reachable] = mechanism.feasible(q[reachable], flat[reachable])
    # The torque set is validated here, once; the force nodes take it as it is.
    values: dict[str, Any] = {"pose": flat[feasible], "joints": q[feasible], "loading": loading,
                              "torques": loading.torque_set(mechanism)}
    order = closure(names, mechanism, loading)
    unknown = None
    for name in order:
        values[name] = QUANTITIES[name].run(values, mechanism)
        if name == "torque_bias" and not np.all(np.isfinite(values[name])):
            # A gravity torque that cannot be differenced (a pose the model classes singular,
            # no neighbouring pose on one side): the loaded set there is unknown. Computed with
            # no bias, then those poses' loaded figures are set to nan (-1 for classes).
            unknown = ~np.all(np.isfinite(values[name]), axis=-1)
            values[name] = np.where(unknown[:, None], 0.0, values[name])
        if name == "torque_bias":
            nodes.add_bias(values)
        if unknown is not None and name in BIASED_NODES:
            values[name] = np.where(unknown, -1 if QUANTITIES[name].categorical else np.nan, values[name])
    out = {}
    for name in names:
        node = QUANTITIES[name]
        if node.categorical:
            full = np.full(flat.shape[0], -1, dtype=np.int16)
        else:
            sub = values[name]
            full = np.full((flat.shape[0],) + np.shape(sub)[1:], np.nan)
        full[feasible] = values[name]
        out[name] = full.reshape(batch + full.shape[1:])
    joints = np.where(feasible[:, None], q, np.nan).reshape(batch + (mechanism.n_joints,))
    return Evaluation(feasible=feasible.reshape(batch), joints=joints, values=out,
                      computed=("joints",) + tuple(order))


def shipped_graph(names, mechanism, loading: Loading) -> bool:
    """Whether every node the request reaches has its shipped definition (this module's table and
    ``quantity_nodes``).

    A compiled kernel computes those definitions; where one was replaced (a test's guard, an
    experiment with a new formula) the graph no longer says what the kernel computes, and the graph runs.
    """
    shipped = ("metrics.quantities", "metrics.quantity_nodes")
    return all(QUANTITIES[n].compute.__module__ in shipped for n in closure(names, mechanism, loading))


def compiled_kernel(mechanism, names, loading: Loading):
    """The compiled kernel of this request (``metrics.kernels.find``) where the graph is the shipped one, else None."""
    fused = kernels.find(mechanism, names, loading)
    return fused if fused is not None and shipped_graph(names, mechanism, loading) else None


def compiled_evaluate(kernel, points: np.ndarray, names, loading: Loading, *, threads: bool = True) -> Evaluation:
    """``evaluate`` by a compiled ``kernel`` (``compiled_kernel``); points it hands back take the numpy path."""
    def fallback(at):
        return evaluate(kernel.mechanism, at, names, loading=loading)

    feasible, joints, values = kernels.evaluate(kernel, points, names, fallback, threads=threads)
    return Evaluation(feasible=feasible, joints=joints, values=values,
                      computed=("joints",) + tuple(closure(names, kernel.mechanism, loading)))


def singularity_families() -> tuple[str, ...]:
    """Registered mechanism kinds with a singularity analysis: those ``singularity`` maps work for.

    Read from the registry (``kinematics.registry.MECHANISMS``) and each class's
    ``singularity_classes``, so a help text built on it follows the models.

    Returns
    -------
    tuple of str
        Registry keys, in the registry's order.

    Examples
    --------
    >>> "inverse3" in singularity_families(), "fivebar" in singularity_families()
    (False, True)
    """
    return tuple(kind for kind, cls in MECHANISMS.items() if cls.singularity_classes)


def quantity_scope_help() -> str:
    """``"singularity: fivebar, delta, ... devices only"``: which families compute the ``singularity`` map.

    Returns
    -------
    str
        For a command's ``--quantity`` help.
    """
    return f"singularity: {', '.join(singularity_families())} devices only"
