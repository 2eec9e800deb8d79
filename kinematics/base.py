"""The models' common base: ``MechanismBase`` (the defaults of the contract) and ``ParamInfo``.

The contract itself, the ``Mechanism`` protocol, is ``kinematics.contract``. Batch axes lead,
as in ``numpy.linalg``: joints ``(..., n)``, task points ``(..., m)``, Jacobians ``(..., m, n)``.
SI units and radians throughout. The models' argument checks are in ``kinematics.validation``,
the array types in ``kinematics.arrays``, angle wrapping into joint limits in
``kinematics.angles``.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import gravity as _gravity
from . import units
from .arrays import BoolArray, FloatArray  # noqa: F401  (re-exported: the types live in kinematics.arrays)

# Re-exported for callers that import them from here (app/cli.py, app/gui, resources/schema.py).
from .units import task_display_units, task_from_si, task_scales, task_to_si  # noqa: F401
from .validation import as_points


@dataclass(frozen=True, slots=True)
class ParamInfo:
    """How a person sees one model parameter: its name, unit and scale to SI.

    ``scale`` converts the displayed unit to SI (mm -> m is 1e-3, deg -> rad is pi/180).
    ``labels`` names the entries of a vector parameter, e.g. ("theta_0", "p1", "p2").
    """

    name: str
    unit: str
    scale: float
    description: str
    labels: tuple[str, ...] = ()
    choices: tuple[str, ...] = ()

    @property
    def is_vector(self) -> bool:
        """Whether the parameter is a vector with named entries (``labels`` not empty).

        Returns
        -------
        bool

        Examples
        --------
        >>> ParamInfo("gear_ratios", "", 1.0, "Transmission ratio", ("theta_1", "theta_2")).is_vector
        True
        """
        return bool(self.labels)

    def to_si(self, value: float) -> float:
        """Display unit -> SI (``units.to_si``: 350 mm is exactly 0.35 m).

        Parameters
        ----------
        value : float
            The number in the display unit ``unit``.

        Returns
        -------
        float
            The value in SI units.

        Examples
        --------
        >>> ParamInfo("proximal", "mm", 1e-3, "Proximal link length").to_si(350)
        0.35
        """
        return units.to_si(value, self.unit, self.scale)

    def from_si(self, value: float) -> float:
        """SI -> display unit: the shortest decimal that ``to_si`` maps back to ``value`` (``units.from_si``).

        Parameters
        ----------
        value : float
            The value in SI units.

        Returns
        -------
        float
            The value in the display unit ``unit``.

        Examples
        --------
        >>> ParamInfo("proximal", "mm", 1e-3, "Proximal link length").from_si(0.35)
        350.0
        """
        return units.from_si(value, self.unit, self.scale)


def joint_side(motor: ArrayLike, gear_ratios: ArrayLike) -> FloatArray:
    """Joint-side effort ``motor_u * gear_ratio_u`` of each joint (N m, or N for a prismatic
    joint): the one place a motor's torque rating meets its transmission.

    Examples
    --------
    >>> joint_side([0.1, 0.2], [10.0, 5.0]).tolist()
    [1.0, 1.0]
    """
    return np.asarray(motor, float) * np.asarray(gear_ratios, float)


def memoised(method):
    """A model's no-argument method computed once per model: it depends on the (immutable) parameters alone.

    The value is kept in the instance's ``__dict__`` (a model never changes; ``replace`` makes a new
    one), so a map asking for ``bodies`` once per block builds and validates them once.
    """
    key = f"_memo_{method.__name__}"

    @functools.wraps(method)
    def cached(self):
        store = self.__dict__
        if key not in store:
            store[key] = method(self)
        return store[key]

    return cached


def joint_speed(motor_speeds: ArrayLike | None, gear_ratios: ArrayLike) -> FloatArray | None:
    """Joint-side speed ``motor_speed_u / gear_ratio_u`` of each joint (rad/s, or m/s for a prismatic
    joint), or ``None`` without motor speeds: where a motor's speed meets its transmission.

    Examples
    --------
    >>> joint_speed([500.0, 100.0], [10.0, 5.0]).tolist()
    [50.0, 20.0]
    >>> joint_speed(None, [10.0]) is None
    True
    """
    if motor_speeds is None:
        return None
    return np.asarray(motor_speeds, float) / np.asarray(gear_ratios, float)


class MechanismBase:
    """Common behaviour: immutable parameters, ``replace``, parameter listing, and the contract's
    defaults.

    ``kinematics.contract.Mechanism`` documents every member a model implements (arguments,
    shapes, units, what raises); a method here says only what its default does, and a model's
    override only what is particular to that model.
    """

    params: Any
    #: ParamInfo for each field of ``params``, in display order.
    PARAM_INFO: tuple[ParamInfo, ...] = ()

    def __init__(self, params: Any) -> None:
        object.__setattr__(self, "params", params)
        self._check_torque_products()

    #: Actuator ratings whose product with ``gear_ratios`` is a joint-side limit (``torque_limits``).
    _RATINGS = (("motor_torques", "N m"), ("peak_motor_torques", "N m"), ("motor_forces", "N"))

    def _check_torque_products(self) -> None:
        """Raise a ValueError naming both parameters where ``rating_u * gear_ratio_u`` leaves the floats.

        Each factor is checked on its own by the parameters; their product, the joint-side limit
        ``t_u``, can still overflow to ``inf`` (1e308 N m through a ratio of 10) or underflow to 0
        (1e-300 N m through 1e-300), which no force figure can be computed from.
        """
        gears = getattr(self.params, "gear_ratios", None)
        if gears is None:
            return
        labels = {info.name: info.labels for info in self.PARAM_INFO}
        g = np.asarray(gears, float)
        for name, unit in self._RATINGS:
            rating = getattr(self.params, name, None)
            if rating is None:
                continue
            r = np.asarray(rating, float)
            if r.shape != g.shape:
                continue
            with np.errstate(over="ignore", under="ignore"):
                t = r * g
            bad = np.flatnonzero(~np.isfinite(t) | (t <= 0) | (t < np.finfo(float).tiny))
            if len(bad):
                k = int(bad[0])
                label = labels.get(name, ())[k] if k < len(labels.get(name, ())) else str(k)
                how = "overflows" if not np.isfinite(t[k]) else "underflows"
                raise ValueError(f"{name}[{label}] x gear_ratios[{label}] = {r[k]:g} {unit} x {g[k]:g} {how} "
                                 f"the floating-point range: the joint-side limit must be a normal positive number")
        speeds = getattr(self.params, "motor_speeds", None)
        if speeds is not None and np.shape(speeds) == g.shape:
            with np.errstate(over="ignore", under="ignore"):
                v = np.asarray(speeds, float) / g
            bad = np.flatnonzero(~np.isfinite(v) | (v < np.finfo(float).tiny))
            if len(bad):
                k = int(bad[0])
                label = labels.get("motor_speeds", labels.get("gear_ratios", ()))
                label = label[k] if k < len(label) else str(k)
                how = "overflows" if not np.isfinite(v[k]) else "underflows"
                raise ValueError(f"motor_speeds[{label}] / gear_ratios[{label}] = {speeds[k]:g} / {g[k]:g} {how} the "
                                 f"floating-point range: the joint-side speed limit must be a normal positive number")

    def __setattr__(self, key: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable; use replace(**changes)")

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.params == self.params  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((type(self), self.params))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.params!r})"

    def replace(self, **changes: Any) -> Self:
        """Return a new model with some parameters changed (validated like the constructor)."""
        names = {f.name for f in dataclasses.fields(self.params)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ValueError(
                f"{type(self).__name__} has no parameter {unknown[0]!r}; known: {', '.join(sorted(names))}"
            )
        return type(self)(dataclasses.replace(self.params, **changes))

    def torque_limits(self) -> FloatArray:
        """Joint-side torque limit of each actuator, ``t_u = motor_torque_u * gear_ratio_u``, shape (n,)."""
        return joint_side(self.params.motor_torques, self.params.gear_ratios)

    def peak_torque_limits(self) -> FloatArray | None:
        """Joint-side peak torque of each actuator, shape (n,); ``None`` by default: no peak rating.

        A model whose source gives a peak (stall, short-time) torque as well as the continuous
        one overrides this; ``torque_limits`` is always the continuous rating.
        """
        return None

    def joint_speed_limits(self) -> FloatArray | None:
        """Largest speed of each actuator, joint side, ``motor_speed_u / gear_ratio_u``, shape (n,); ``None``
        where the model's ``params.motor_speeds`` is (the speeds are not given).

        A rotor turns ``N_u`` times faster than its joint, so the gear ratio that multiplies the
        joint's torque (``torque_limits``) divides its speed.
        """
        return joint_speed(getattr(self.params, "motor_speeds", None), self.params.gear_ratios)

    #: Whether the model knows its bodies (``bodies``, ``rotor_inertias``, ``body_poses``): gravity,
    #: mass matrices, effective masses and accelerations (``kinematics.dynamics``).
    has_mass_model: bool = False
    #: Which coordinates ``body_poses`` is differenced in: ``"joint"`` (``q``, serial arms) or
    #: ``"task"`` (``x`` through the closed-form ``inverse``, closed chains).
    mass_coordinates: str = "joint"

    def _no_mass_model(self) -> ValueError:
        return ValueError(f"{type(self).__name__} has no mass model (bodies' masses and inertias): no gravity, "
                          f"effective mass or acceleration")

    def bodies(self) -> tuple:
        """The rigid bodies of the mass model (``kinematics.bodies.Body``), in ``body_poses`` order.

        Raises
        ------
        ValueError
            Without a mass model.
        """
        raise self._no_mass_model()

    def rotor_inertias(self) -> FloatArray:
        """Each actuator's rotor inertia, motor side, shape (n,), kg m^2 (``params.rotor_inertias``).

        Raises
        ------
        ValueError
            Without a mass model.
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        return np.asarray(self.params.rotor_inertias, float)

    def reflected_rotor_inertias(self) -> FloatArray:
        """``J_u N_u^2`` (n,): each rotor's inertia felt at its joint through the transmission ``N_u``
        (``params.gear_ratios``), kg m^2 (kg for a prismatic joint).

        Raises
        ------
        ValueError
            Without a mass model.
        """
        with np.errstate(over="ignore", under="ignore"):     # a ratio of 1e300: an unbounded rotor, inf
            return self.rotor_inertias() * np.asarray(self.params.gear_ratios, float) ** 2

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Each body frame's orientation ``R`` (..., k, 3, 3) and origin (..., k, 3), base frame, m.

        Parameters
        ----------
        q : array_like, shape (..., n)
        x : array_like, shape (..., m)
            A consistent pose; ``nan`` gives ``nan``.

        Raises
        ------
        ValueError
            Without a mass model.
        """
        raise self._no_mass_model()

    def body_velocities(self, q: ArrayLike, x: ArrayLike):
        """The bodies' exact velocity Jacobians ``(jv, jw, R, G)``, component-first (the contract's shapes).

        Raises
        ------
        ValueError
            Without a mass model.
        """
        raise self._no_mass_model()

    def mass_matrix(self, q: ArrayLike, x: ArrayLike | None = None, *, rotors: bool = True) -> FloatArray:
        """Joint-space mass matrix ``M(q)`` (..., n, n): ``1/2 qdot^T M qdot`` is the kinetic energy.

        Includes each rotor's ``J_u N_u^2`` unless ``rotors=False``. Task-placed models give
        ``J^T Lambda J``; a redundantly actuated one (``n > m``) has no ``M`` over its dependent
        joints and raises.

        Returns
        -------
        ndarray, shape (..., n, n)
            kg m^2 (revolute), kg (prismatic).
        """
        from . import dynamics
        q = as_points("q", q, self.n_joints)
        x = self.forward(q)[0] if x is None else as_points("x", x, self.task_dim)
        if self.mass_coordinates == "joint":
            return dynamics.kinetic_form(self, q, x, rotors=rotors)
        if self.n_joints != self.task_dim:
            raise ValueError(f"{type(self).__name__} is redundantly actuated ({self.n_joints} actuators, "
                             f"{self.task_dim} task coordinates): its joints are not independent, use task_inertia")
        jac = self.jacobian(q, x)
        lam = dynamics.kinetic_form(self, q, x, rotors=rotors)
        return np.einsum("...ma,...mk,...kb->...ab", jac, lam, jac)

    def task_inertia(self, q: ArrayLike, x: ArrayLike | None = None, *, rotors: bool = True) -> FloatArray:
        """Task-space inertia ``Lambda`` (..., m, m), ``(J M^-1 J^T)^-1``: what the hand feels.

        Task-placed models give the bodies' kinetic form in ``x`` directly (no inverse of J);
        joint-placed ones ``J^-T M J^-1`` by two solves (``inf``/``nan`` where J is singular).

        Returns
        -------
        ndarray, shape (..., m, m)
            kg (length rows and columns), kg m^2 (angles), kg m (mixed).
        """
        from . import dynamics
        q = as_points("q", q, self.n_joints)
        x = self.forward(q)[0] if x is None else as_points("x", x, self.task_dim)
        if self.mass_coordinates == "task":
            return dynamics.kinetic_form(self, q, x, rotors=rotors)
        mass = dynamics.kinetic_form(self, q, x, rotors=rotors)
        force_map = self.force_map(q, x)                       # J^-T, finite where J is regular
        return np.einsum("...an,...nk,...bk->...ab", force_map, mass, force_map)

    def coordinate_rates_to_twist(self, x: ArrayLike) -> FloatArray:
        """``T`` (..., m, m) with ``xi = T xdot``: the identity for a task without orientation coordinates.

        A model with orientation coordinates whose ``jacobian`` maps to twists overrides it.
        """
        x = as_points("x", x, self.task_dim)
        return np.broadcast_to(np.eye(self.task_dim), x.shape[:-1] + (self.task_dim, self.task_dim)).copy()

    def body_masses(self) -> FloatArray:
        """Body masses (k,), kg, of ``bodies``."""
        return np.array([b.mass for b in self.bodies()], float)

    def centres_of_mass(self, q: ArrayLike) -> FloatArray:
        """Centres of mass (..., k, 3) in the base frame, m, of ``bodies`` placed by ``body_poses``."""
        from .bodies import body_arrays, centres
        q = as_points("q", q, self.n_joints)
        rot, org = self.body_poses(q, self.forward(q)[0])
        return centres(rot, org, body_arrays(self.bodies())[1])

    def centres_of_mass_jacobian(self, q: ArrayLike) -> FloatArray:
        """``dp_i/dq`` (..., k, 3, n), from the model's exact ``body_velocities`` (``kinematics.dynamics``)."""
        from . import dynamics
        q = as_points("q", q, self.n_joints)
        return dynamics.centre_jacobians(self, q, self.forward(q)[0])

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike) -> FloatArray:
        """``V(q) = -sum_i m_i g . p_i(q)`` (...), J (``kinematics.gravity.potential_energy``)."""
        return _gravity.potential_energy(self.body_masses(), self.centres_of_mass(q), gravity)

    def gravity_torque(self, q: ArrayLike, gravity: ArrayLike) -> FloatArray:
        """``dV/dq`` (..., n), N m: the torque the joints spend holding the links (``kinematics.gravity``).

        Analytic, from ``centres_of_mass_jacobian``; the force set's torque bias.
        """
        return _gravity.gravity_torque(self.body_masses(), self.centres_of_mass_jacobian(q), gravity)

    # -- contract defaults (see ``kinematics.contract.Mechanism``) --------------------------------------
    @property
    def task_units(self) -> tuple[str, ...]:
        """SI unit of each task coordinate; all ``"m"`` unless a model says otherwise, length ``m``."""
        return ("m",) * self.task_dim

    @property
    def joint_units(self) -> tuple[str, ...]:
        """SI unit of each actuated joint; all ``"rad"`` (revolute) unless a model says otherwise, length ``n``."""
        return ("rad",) * self.n_joints

    @property
    def has_orientation(self) -> bool:
        """Some task coordinate is an angle (``"rad"`` in ``task_units``): the device holds wrenches."""
        return "rad" in self.task_units

    @property
    def is_redundant(self) -> bool:
        """More actuators than task coordinates (``n > m``): the force set is a zonotope of ``force_map``."""
        return self.n_joints > self.task_dim

    @property
    def characteristic_length(self) -> float | None:
        """Length (m) moments are scaled by; ``None`` for a positioning device (no orientation)."""
        return None

    #: Names of the singularity codes (index = code); ``()``: no singularity analysis.
    singularity_classes: tuple[str, ...] = ()

    @property
    def revolution(self) -> tuple[float, float, float] | None:
        """``(lower, upper, offset)`` when the workspace is the map's (x, z) slice revolved about
        the base's z axis by the first joint over ``[lower, upper]`` (rad), the slice's plane
        ``offset`` (m) from that axis; ``None`` for any other model (the default).
        """
        return None

    @property
    def dexterous_annulus(self) -> tuple[float, float] | None:
        """Inner and outer radius (m) of paper 002's dexterous annulus about the base's centre;
        ``None`` for a model the paper defines none for (the default)."""
        return None

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., m, n) with ``xdot = J qdot``; every model defines it."""
        raise NotImplementedError(f"{type(self).__name__} must define jacobian(q, x=None)")

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = J^-T`` (..., m, m): the wrench ``w = A tau`` of actuator efforts ``tau`` (statics ``tau = J^T w``).

        The default for square, non-redundant models; ``nan`` where ``J`` is singular or not
        finite (one bad pose never aborts a batch). Redundant models define their own.
        """
        if self.is_redundant:
            raise NotImplementedError(f"{type(self).__name__} is redundant and must define force_map(q, x=None)")
        from .rotations import batched_inverse
        inv, ok = batched_inverse(self.jacobian(q, x))
        return np.where(ok[..., None, None], np.swapaxes(inv, -1, -2), np.nan)

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """Singularity code of each pose, int8 (...); zeros where the model has no analysis."""
        q = as_points("q", q, self.n_joints)
        return np.zeros(q.shape[:-1], np.int8)

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Actuators at an inverse singularity, bool (..., n); all ``False`` by default."""
        q = as_points("q", q, self.n_joints)
        return np.zeros(q.shape, bool)

    def singular_loci(self) -> dict[str, FloatArray]:
        """Task points (k, m) just inside each singular locus, by name; ``{}`` by default (``metrics.suprema``)."""
        return {}

    def parameter_table(self) -> list[tuple[ParamInfo, Any]]:
        """Each parameter's info with its value in display units (vectors as tuples).

        Returns
        -------
        list of (ParamInfo, object)
            One row per entry of ``PARAM_INFO``, in display order: a float, a tuple of floats for a
            vector parameter, or the string of a choice.
        """
        rows = []
        for info in self.PARAM_INFO:
            value = getattr(self.params, info.name)
            if info.choices:
                rows.append((info, value))
            elif info.is_vector:
                rows.append((info, tuple(info.from_si(v) for v in value)))
            else:
                rows.append((info, info.from_si(value)))
        return rows

    def replace_display(self, **changes: Any) -> Self:
        """Like ``replace`` but with values in display units (mm, deg), as a person types them.

        Parameters
        ----------
        **changes
            Parameter names and their new values in the display units of ``PARAM_INFO``; a vector
            parameter takes a sequence of one number per label.

        Returns
        -------
        MechanismBase
            A new model of the same class.

        Raises
        ------
        ValueError
            For an unknown name, a value that is not a number, or a vector of the wrong length.
        """
        infos = {info.name: info for info in self.PARAM_INFO}
        si: dict[str, Any] = {}
        for name, value in changes.items():
            info = infos.get(name)
            if info is None:
                raise ValueError(f"{type(self).__name__} has no parameter {name!r}; known: {', '.join(infos)}")
            if info.choices:
                si[name] = value
            elif info.is_vector:
                if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
                    raise ValueError(
                        f"{name} needs {len(info.labels)} values ({', '.join(info.labels)}), got {value!r}"
                    )
                si[name] = tuple(info.to_si(_number(name, v)) for v in value)
            else:
                si[name] = info.to_si(_number(name, value))
        try:
            return self.replace(**si)
        except ValueError as exc:
            raise ValueError(_in_display_units(str(exc), changes, si, infos)) from None


def _in_display_units(message: str, typed: dict[str, Any], si: dict[str, Any], infos: dict) -> str:
    """A validation message about a value typed in display units, in those units.

    The models check SI values ("proximal must be a positive finite number in m, got -0.005");
    a person typed -5 mm, so the message names what they typed: "... in mm, got -5".
    """
    for name, value in typed.items():
        info = infos[name]
        if info.choices or info.is_vector or info.scale == 1.0 or not message.startswith(f"{name} "):
            continue
        si_unit = {"mm": "m", "deg": "rad", "cm": "m", "g": "kg"}.get(info.unit)
        tail = f", got {si[name]!r}"
        if message.endswith(tail):
            message = message[: -len(tail)] + f", got {value!r}"
            if si_unit is not None:
                message = message.replace(f" in {si_unit},", f" in {info.unit},")
    return message


def _number(name: str, value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None


def singular_limit(jac: FloatArray, legs: BoolArray, direct: BoolArray) -> FloatArray:
    """``J`` (..., m, n) with its exact value where the model classes a pose singular.

    The five-bar's rule, for every model with a singularity analysis: an actuator at an inverse
    singularity (``legs``, its leg stretched or folded) moves the task point not at all, so its
    column is exactly 0 (all of them: ``J = 0``); at a direct singularity the task point moves with
    the actuators locked, so every entry is ``inf``. Rounding alone leaves a column of ~1e-17 m/rad
    there, and every metric downstream would read that noise as a force of 1e16 N; with the exact
    value they take their singular limits (condition number and facet distances ``inf``).

    Parameters
    ----------
    jac : ndarray, shape (..., m, n)
        The computed Jacobian.
    legs : ndarray of bool, shape (..., n)
        Actuators at an inverse singularity (``singular_legs``).
    direct : ndarray of bool, shape (...)
        Poses at a direct singularity.

    Returns
    -------
    ndarray, shape (..., m, n)
        A new array; ``+ 0.0`` leaves no ``-0`` entries.
    """
    jac = np.where(np.asarray(legs, bool)[..., None, :], 0.0, jac)
    return np.where(np.asarray(direct, bool)[..., None, None], np.inf, jac) + 0.0
