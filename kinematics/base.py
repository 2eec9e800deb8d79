"""Shared pieces of every mechanism model: array types, validation, the protocol.

Batch axes lead, as in ``numpy.linalg``: joints ``(..., n)``, task points ``(..., m)``,
Jacobians ``(..., m, n)``. SI units and radians throughout.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Protocol, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import units, validation

# Re-exported for callers that import them from here (app/cli.py, app/gui, resources/schema.py).
from .units import task_display_units, task_from_si, task_scales, task_to_si  # noqa: F401

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


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
        return bool(self.labels)

    def to_si(self, value: float) -> float:
        """Display unit -> SI (``units.to_si``: 350 mm is exactly 0.35 m)."""
        return units.to_si(value, self.unit, self.scale)

    def from_si(self, value: float) -> float:
        """SI -> display unit: the shortest decimal that ``to_si`` maps back to ``value`` (``units.from_si``)."""
        return units.from_si(value, self.unit, self.scale)


# The validators' old positional names, for the models and the metrics modules that call them;
# the implementations (and their messages) are in ``kinematics.validation``.
def positive_finite(name: str, value: Any, unit: str = "") -> float:
    """``validation.validate_positive_number(value, name=name, unit=unit)``."""
    return validation.validate_positive_number(value, name=name, unit=unit)


def positive_vector(name: str, values: Any, labels: tuple[str, ...], unit: str = "") -> tuple[float, ...]:
    """``validation.validate_positive_vector(values, name=name, labels=labels, unit=unit)``."""
    return validation.validate_positive_vector(values, name=name, labels=labels, unit=unit)


def finite_angles(name: str, values: Any, labels: tuple[str, ...]) -> tuple[float, ...]:
    """``validation.validate_angles(values, name=name, labels=labels)``."""
    return validation.validate_angles(values, name=name, labels=labels)


def choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    """``validation.validate_choice(value, name=name, choices=choices)``."""
    return validation.validate_choice(value, name=name, choices=choices)


def as_points(name: str, x: ArrayLike, m: int) -> FloatArray:
    """``validation.validate_points(x, name=name, m=m)``: shape (..., m) float64."""
    return validation.validate_points(x, name=name, m=m)


class Mechanism(Protocol):
    """Everything a caller may ask of a mechanism model: ``n`` actuated joints, ``m`` task coordinates.

    Callers trust this contract and never probe a model with ``hasattr``/``getattr``/``inspect``;
    ``MechanismBase`` gives every optional part a default, and
    ``tests/kinematics/test_contract.py`` checks every registered kind and every preset keeps it.

    Attributes
    ----------
    params : frozen dataclass
        The model's parameters (SI units, radians).
    n_joints : int
        ``n``, the number of actuated joints.
    task_dim : int
        ``m``, the number of task coordinates.
    joint_names, task_names : tuple of str
        Names of the ``n`` actuated joints and of the ``m`` task coordinates.
    task_units : tuple of str
        SI unit of each task coordinate, ``"m"`` or ``"rad"`` (default all ``"m"``), length ``m``.
    joint_units : tuple of str
        SI unit of each actuated joint, ``"rad"`` (revolute) or ``"m"`` (prismatic), length ``n``.
    has_orientation : bool
        Some task coordinate is an angle: the device holds wrenches, not only forces.
    is_redundant : bool
        More actuators than task coordinates (``n > m``): the force set is the zonotope
        ``A [-t, t]^n`` of ``force_map``.
    characteristic_length : float or None
        Length (m) moments are divided by to compare them with forces; ``None`` when the
        task has no orientation.
    singularity_classes : tuple of str
        Names of the codes ``singularity`` returns (index = code); ``()`` when the model has
        no singularity analysis.
    """

    params: Any

    @property
    def n_joints(self) -> int: ...
    @property
    def task_dim(self) -> int: ...
    @property
    def joint_names(self) -> tuple[str, ...]: ...
    @property
    def task_names(self) -> tuple[str, ...]: ...
    @property
    def task_units(self) -> tuple[str, ...]: ...
    @property
    def joint_units(self) -> tuple[str, ...]: ...
    @property
    def has_orientation(self) -> bool: ...
    @property
    def is_redundant(self) -> bool: ...
    @property
    def characteristic_length(self) -> float | None: ...
    @property
    def singularity_classes(self) -> tuple[str, ...]: ...

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Task point ``x`` (..., m) of joints ``q`` (..., n), and whether it assembles (...)."""
        ...

    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Joints ``q`` (..., n) reaching ``x`` (..., m), and ``reachable`` (...); ``nan`` where not."""
        ...

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., m, n) with ``xdot = J qdot`` at joints ``q`` (..., n) and pose ``x`` (..., m)."""
        ...

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A`` (..., m, n): the task wrench ``w = A tau`` per unit actuator effort ``tau``."""
        ...

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """Singularity code (index into ``singularity_classes``) of each pose, int8 (...)."""
        ...

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Which actuators are at an inverse singularity, bool (..., n)."""
        ...

    def singular_loci(self) -> dict[str, FloatArray]:
        """Task points (k, m) next to each kind of singularity (``metrics.suprema``); may be empty."""
        ...

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Whether joints ``q`` (..., n) at pose ``x`` (..., m) respect every limit, bool (...)."""
        ...

    def torque_limits(self) -> FloatArray:
        """Largest effort of each actuator (N m or N, joint side), shape (n,)."""
        ...

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline through the links for drawing, shape (..., k, d) with ``d`` 2 or 3, m."""
        ...

    def replace(self, **changes: Any) -> Self:
        """A new model with some parameters (SI) changed, validated like the constructor."""
        ...


class MechanismBase:
    """Common behaviour: immutable parameters, ``replace``, parameter listing."""

    params: Any
    #: ParamInfo for each field of ``params``, in display order.
    PARAM_INFO: tuple[ParamInfo, ...] = ()

    def __init__(self, params: Any) -> None:
        object.__setattr__(self, "params", params)

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
        return np.asarray(self.params.motor_torques, float) * np.asarray(self.params.gear_ratios, float)

    # -- contract defaults (see ``Mechanism``) ------------------------------------------
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

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., m, n) with ``xdot = J qdot``; every model defines it."""
        raise NotImplementedError(f"{type(self).__name__} must define jacobian(q, x=None)")

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = J^-T`` (..., m, m): the wrench ``w = A tau`` of actuator efforts ``tau`` (statics ``tau = J^T w``).

        The default for square, non-redundant models; ``nan`` where ``J`` is singular or not
        finite (one bad pose never aborts a batch). Redundant models define their own.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        x : array_like, shape (..., m), optional
            The pose of ``q`` (computed by the model when not given).

        Returns
        -------
        ndarray, shape (..., m, n)
        """
        if self.is_redundant:
            raise NotImplementedError(f"{type(self).__name__} is redundant and must define force_map(q, x=None)")
        from .rotations import batched_inverse  # local: rotations imports this module
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
        """Each parameter's info with its value in display units (vectors as tuples)."""
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
        """Like ``replace`` but with values in display units (mm, deg), as a person types them."""
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
                    raise ValueError(f"{name} needs {len(info.labels)} values ({', '.join(info.labels)}), got {value!r}")
                si[name] = tuple(info.to_si(_number(name, v)) for v in value)
            else:
                si[name] = info.to_si(_number(name, value))
        return self.replace(**si)


def _number(name: str, value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None


def wrap_into(angle: FloatArray, lower: float, upper: float) -> tuple[FloatArray, BoolArray]:
    """Shift ``angle`` by a multiple of 2 pi into ``[lower, upper]`` where possible.

    Returns the shifted angle and whether it lies inside. Where no shift fits, the angle is
    shifted to just above ``lower`` and reported outside.
    """
    two_pi = 2.0 * np.pi
    # floor instead of np.mod: the same shift, several times faster on large batches.
    shifted = angle - two_pi * np.floor((angle - lower) / two_pi)
    return shifted, shifted <= upper
