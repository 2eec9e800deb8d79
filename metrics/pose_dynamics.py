"""What the hand feels at one pose: masses, acceleration capability and weight (``metrics.dynamics``).

The pose counterpart of the map quantities ``apparent_mass_min`` ... ``weight``: the same graph
(``metrics.quantities.evaluate``) at one point, so a pose and a map agree, plus the per-axis
figures of paper 001's Table X (effective mass ``Lambda_ii``, peak acceleration = peak force
along the axis over that mass).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinematics.arrays import FloatArray

from . import dynamics, wrenches
from .ellipsoids import Ellipsoid, _left_svd, actuator_limits
from .loading import Loading
from .quantities import evaluate
from .spec_sheet import axis_capabilities

#: The map quantities a pose's dynamic summary shares with maps.
DYNAMIC_QUANTITIES = ("mass_matrices", "apparent_mass_min", "apparent_mass_max", "mass_condition_number",
                      "isotropic_acceleration", "weight")


@dataclass(frozen=True)
class PoseDynamics:
    """Masses and accelerations at one pose. SI units.

    Attributes
    ----------
    task_inertia : ndarray, shape (m, m)
        ``Lambda``, kg on length rows and columns, kg m^2 on angles (kg m mixed).
    effective_mass : ndarray, shape (m,)
        ``Lambda_ii`` per task axis (paper 001 Table X "Eff Mass"), kg or kg m^2.
    apparent_mass : ndarray, shape (m,)
        ``1 / (Lambda^-1)_ii``: what a hand pushing along axis i alone feels, kg or kg m^2.
    apparent_mass_range : tuple of 2 float
        Smallest and largest apparent mass over directions of a pure force, kg.
    mass_condition_number : float
        Their ratio.
    isotropic_acceleration : float
        m/s^2 (at zero angular acceleration for a device with orientation freedoms).
    peak_acceleration : ndarray, shape (m,)
        Peak pure force (or moment) along each axis, the smaller of its two senses, at the
        ``peak_rating`` over ``effective_mass``, m/s^2 (rad/s^2); gravity off (paper 001 Table X).
    peak_rating : str
        The rating ``peak_acceleration`` uses: ``"peak"`` where the device has one, else ``"continuous"``.
    weight : float
        Force the hand holds to keep the handle still against ``gravity``, N.
    gravity : tuple of 3 float
        m/s^2 in the base frame (the loading's, upright when its gravity is off).
    acceleration_ellipsoid : Ellipsoid
        ``{J M^-1 tau : |diag(1/t) tau| <= 1}`` with ``t`` the loading's torque limits (pycapacity's
        ``acceleration_ellipsoid``), gravity off: radii (r,) in m/s^2, largest first, and unit axes
        as columns (r, r); for a device with orientation freedoms its linear part (the force rows,
        as the velocity ellipsoid of ``metrics.pose``). ``nan`` where the model has no mass matrix.
    rotors : bool
        Whether the rotors' ``J N^2`` is included (always true here; ``mass_matrix(rotors=False)`` omits it).
    """

    task_inertia: FloatArray
    effective_mass: FloatArray
    apparent_mass: FloatArray
    apparent_mass_range: tuple[float, float]
    mass_condition_number: float
    isotropic_acceleration: float
    peak_acceleration: FloatArray
    peak_rating: str
    weight: float
    gravity: tuple[float, float, float]
    acceleration_ellipsoid: Ellipsoid
    rotors: bool = True


def analyse_dynamics(mechanism, x, *, loading: Loading | None = None) -> PoseDynamics:
    """Masses, accelerations and weight at task point ``x`` (m,), m.

    Raises
    ------
    ValueError
        Where the mechanism has no mass model (the reason, never zeros).
    """
    if not mechanism.has_mass_model:
        raise mechanism._no_mass_model()
    loading = loading or Loading()
    x = np.asarray(x, float)
    ev = evaluate(mechanism, x[None], DYNAMIC_QUANTITIES, loading=loading)
    v = {k: np.asarray(val)[0] for k, val in ev.values.items()}
    lam, mob = v["mass_matrices"][0], v["mass_matrices"][1]
    # Paper 001 Table X: the peak pure force (moment) along each axis, both ways, over Lambda_ii;
    # from the wrench set's facets, so redundant actuation is exact too (metrics.spec_sheet).
    peak_limits = mechanism.peak_torque_limits()
    rating = "peak" if peak_limits is not None else "continuous"
    q, _ = mechanism.inverse(x[None])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):    # torques of 1e300: inf, not a warning
        capability = axis_capabilities(mechanism.force_map(q, x[None])[0], torque_limits=peak_limits
                                       if peak_limits is not None else mechanism.torque_limits())
    forces = np.min(capability, axis=-1)
    from kinematics.gravity import gravity_vector
    gravity = loading.gravity if loading.biased else gravity_vector("upright")
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        peak_acceleration = dynamics.peak_accelerations(forces, lam)
    rows = list(wrenches.force_rows(mechanism))
    image = torque_to_acceleration(mechanism, q[0], x, mob)[rows]
    # pycapacity's acceleration_ellipsoid: the left singular pairs of J M^-1 diag(t).
    t = actuator_limits("torque_limits", loading.torque_limits(mechanism), image.shape[-1])
    axes, radii = _left_svd(image * t)
    accel = Ellipsoid(radii=radii, axes=axes)
    return PoseDynamics(
        task_inertia=lam, effective_mass=dynamics.effective_masses(lam), apparent_mass=dynamics.apparent_masses(mob),
        apparent_mass_range=(float(v["apparent_mass_min"]), float(v["apparent_mass_max"])),
        mass_condition_number=float(v["mass_condition_number"]),
        isotropic_acceleration=float(v["isotropic_acceleration"]),
        peak_acceleration=peak_acceleration, peak_rating=rating,
        weight=float(v["weight"]), gravity=tuple(float(g) for g in gravity), acceleration_ellipsoid=accel)


def torque_to_acceleration(mechanism, q, x, mob) -> FloatArray:
    """``J M^-1`` (m, n) at one pose: the task acceleration per unit joint torque, gravity off.

    A serial arm (``mass_coordinates == "joint"``) has its joint-space ``M(q)``: ``J M^-1`` by a
    solve, finite at a singular ``J``. A closed chain's bodies give ``Lambda`` in task coordinates;
    its ``J M^-1`` with ``M = J^T Lambda J`` is ``Lambda^-1 J^-T``, in general ``Lambda^-1 A`` with
    ``A`` the force map (``f = A tau``, redundant actuation included): ``mob`` (m, m) times it.
    """
    from kinematics.dynamics import kinetic_form
    q, x = np.asarray(q, float), np.asarray(x, float)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if mechanism.mass_coordinates == "joint":
            mass = kinetic_form(mechanism, q[None], x[None])[0]
            jac = mechanism.jacobian(q[None], x[None])[0]
            if not (np.all(np.isfinite(mass)) and np.all(np.isfinite(jac))):
                return np.full(jac.shape, np.nan)
            return np.linalg.solve(mass, jac.T).T
        return np.asarray(mob, float) @ mechanism.force_map(q[None], x[None])[0]


#: The keys ``dynamics_dict`` adds to ``isoforce pose --json`` (``"dynamics"`` alone says why there are none).
DYNAMIC_KEYS = ("effective_mass", "apparent_mass", "apparent_mass_range", "mass_condition_number",
                "isotropic_acceleration", "peak_acceleration", "peak_acceleration_rating", "weight",
                "acceleration_ellipsoid", "dynamics_units", "dynamics")


def dynamics_dict(dyn: PoseDynamics, mechanism) -> dict:
    """Keys of ``dyn`` for ``isoforce pose --json`` (``nan``/``inf`` left to ``print_json``), with their units."""
    mass_units = ["kg" if u == "m" else "kg m^2" for u in mechanism.task_units]
    acc_units = ["m/s^2" if u == "m" else "rad/s^2" for u in mechanism.task_units]

    def listed(a):
        return [float(val) for val in np.asarray(a, float)]

    def scalar(a):
        return float(a)

    return {
        "effective_mass": listed(dyn.effective_mass),
        "apparent_mass": listed(dyn.apparent_mass),
        "apparent_mass_range": [scalar(dyn.apparent_mass_range[0]), scalar(dyn.apparent_mass_range[1])],
        "mass_condition_number": scalar(dyn.mass_condition_number),
        "isotropic_acceleration": scalar(dyn.isotropic_acceleration),
        "peak_acceleration": listed(dyn.peak_acceleration),
        "peak_acceleration_rating": dyn.peak_rating,
        "weight": scalar(dyn.weight),
        # Radii per unit of the torque set (the loading's limits), axes[k] along radii[k].
        "acceleration_ellipsoid": {"radii": listed(dyn.acceleration_ellipsoid.radii),
                                   "axes": [listed(a) for a in np.asarray(dyn.acceleration_ellipsoid.axes).T]},
        "dynamics_units": {"effective_mass": mass_units, "apparent_mass": mass_units,
                           "apparent_mass_range": "kg", "isotropic_acceleration": "m/s^2",
                           "peak_acceleration": acc_units, "weight": "N",
                           "acceleration_ellipsoid.radii": "m/s^2",
                           "note": "links and rotors (J_rotor N^2); weight under gravity "
                                   f"({', '.join(f'{g:g}' for g in dyn.gravity)}) m/s^2"},
    }
