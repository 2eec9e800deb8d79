"""The mechanism contract: the ``Mechanism`` protocol, everything a caller may ask of a model.

Batch axes lead, as in ``numpy.linalg``: joints ``(..., n)``, task points ``(..., m)``,
Jacobians ``(..., m, n)``. SI units and radians throughout. ``kinematics.base.MechanismBase``
gives every optional part a default; ``tests/kinematics/test_contract.py`` checks that every
registered kind and preset keeps the contract.

Most of this module is docstrings: the contract's numpydoc sections (issue 8).
"""
from __future__ import annotations

from typing import Any, Protocol, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .arrays import BoolArray, FloatArray
from .base import ParamInfo  # noqa: F401  (named in the contract's annotations)


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
    def n_joints(self) -> int:
        """``n``, the number of actuated joints.

        Returns
        -------
        int
        """
        ...
    @property
    def task_dim(self) -> int:
        """``m``, the number of task coordinates.

        Returns
        -------
        int
        """
        ...
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the ``n`` actuated joints.

        Returns
        -------
        tuple of str, length ``n``
        """
        ...
    @property
    def task_names(self) -> tuple[str, ...]:
        """Names of the ``m`` task coordinates.

        Returns
        -------
        tuple of str, length ``m``
        """
        ...
    @property
    def task_units(self) -> tuple[str, ...]:
        """SI unit of each task coordinate, ``"m"`` or ``"rad"``.

        Returns
        -------
        tuple of str, length ``m``
        """
        ...
    @property
    def joint_units(self) -> tuple[str, ...]:
        """SI unit of each actuated joint, ``"rad"`` (revolute) or ``"m"`` (prismatic).

        Returns
        -------
        tuple of str, length ``n``
        """
        ...
    @property
    def has_orientation(self) -> bool:
        """Some task coordinate is an angle: the device holds wrenches, not only forces.

        Returns
        -------
        bool
        """
        ...
    @property
    def is_redundant(self) -> bool:
        """More actuators than task coordinates (``n > m``).

        Returns
        -------
        bool
        """
        ...
    @property
    def characteristic_length(self) -> float | None:
        """Length (m) moments are divided by to compare them with forces.

        Returns
        -------
        float or None
            ``None`` when the task has no orientation.
        """
        ...
    @property
    def singularity_classes(self) -> tuple[str, ...]:
        """Names of the codes ``singularity`` returns (index = code).

        Returns
        -------
        tuple of str
            ``()`` when the model has no singularity analysis.
        """
        ...

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Task point ``x`` (..., m) of joints ``q`` (..., n), and whether it assembles (...).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints (rad or m, ``joint_units``).

        Returns
        -------
        x : ndarray, shape (..., m)
            Task point (m, rad); ``nan`` where it does not assemble.
        ok : ndarray of bool, shape (...)
            Whether it assembles.
        """
        ...

    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Joints ``q`` (..., n) reaching ``x`` (..., m), and ``reachable`` (...); ``nan`` where not.

        Parameters
        ----------
        x : array_like, shape (..., m)
            Task points (m, rad).

        Returns
        -------
        q : ndarray, shape (..., n)
            Actuated joints; ``nan`` where unreachable.
        reachable : ndarray of bool, shape (...)
        """
        ...

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., m, n) with ``xdot = J qdot`` at joints ``q`` (..., n) and pose ``x`` (..., m).

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
        ...

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A`` (..., m, n): the task wrench ``w = A tau`` per unit actuator effort ``tau``.

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
        ...

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """Singularity code (index into ``singularity_classes``) of each pose, int8 (...).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        x : array_like, shape (..., m), optional
            The pose of ``q``.

        Returns
        -------
        ndarray of int8, shape (...)
        """
        ...

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Which actuators are at an inverse singularity, bool (..., n).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        x : array_like, shape (..., m), optional
            The pose of ``q``.

        Returns
        -------
        ndarray of bool, shape (..., n)
        """
        ...

    def singular_loci(self) -> dict[str, FloatArray]:
        """Task points (k, m) next to each kind of singularity (``metrics.suprema``); may be empty.

        Returns
        -------
        dict of str to ndarray, shape (k, m)
            Task points (m, rad) by kind of singularity.
        """
        ...

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Whether joints ``q`` (..., n) at pose ``x`` (..., m) respect every limit, bool (...).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        x : array_like, shape (..., m), optional
            The pose of ``q``.

        Returns
        -------
        ndarray of bool, shape (...)
        """
        ...

    def torque_limits(self) -> FloatArray:
        """Largest effort of each actuator (N m or N, joint side), shape (n,).

        Returns
        -------
        ndarray, shape (n,)
            N m (revolute) or N (prismatic).
        """
        ...

    def peak_torque_limits(self) -> FloatArray | None:
        """Peak (short-time) effort of each actuator, joint side, shape (n,); ``None``: no peak rating.

        Returns
        -------
        ndarray, shape (n,), or None
            N m (revolute) or N (prismatic).
        """
        ...

    def joint_speed_limits(self) -> FloatArray | None:
        """Largest speed of each actuator, joint side: the motor's speed over its gear ratio, shape (n,).

        Returns
        -------
        ndarray, shape (n,), or None
            rad/s (revolute) or m/s (prismatic); ``None`` where the model's motor speeds are not
            given (``params.motor_speeds``): no velocity polytope.
        """
        ...

    def coordinate_rates_to_twist(self, x: ArrayLike) -> FloatArray:
        """``T`` (..., m, m) with ``xi = T xdot``: the rates of the task coordinates to the twist ``J`` maps to.

        The identity for a task without orientation coordinates; ``blockdiag(I, J_l(r))`` for a
        position and a rotation vector (``rotations.pose_rates_to_twist``); the Twin-Pantograph's
        5-DOF tilt its own. ``Lambda``, the gravity wrench and ``J`` are all per twist.

        Parameters
        ----------
        x : array_like, shape (..., m)
            Poses (m, rad).

        Returns
        -------
        ndarray, shape (..., m, m)
            ``nan`` where ``x`` is not finite.
        """
        ...

    @property
    def has_mass_model(self) -> bool:
        """Whether the model knows its body masses and centres of mass (a gravity model).

        Returns
        -------
        bool
        """
        ...

    @property
    def mass_coordinates(self) -> str:
        """Which coordinates place the bodies: ``"joint"`` (``q``, serial arms) or ``"task"`` (``x``, closed chains).

        Returns
        -------
        str
        """
        ...

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Each body frame's orientation ``R`` (..., k, 3, 3) and origin (..., k, 3), base frame, m.

        Parameters
        ----------
        q : array_like, shape (..., n)
        x : array_like, shape (..., m)
            A consistent pose; ``nan`` gives ``nan``.

        Returns
        -------
        rotations : ndarray, shape (..., k, 3, 3)
        origins : ndarray, shape (..., k, 3)
            m. Bodies in ``bodies()`` order.

        Raises
        ------
        ValueError
            Without a mass model.
        """
        ...

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[Any, Any, Any, FloatArray | None]:
        """Exact velocity Jacobians of the ``k`` bodies, component-first (``kinematics.bodies``).

        Per unit rate of the ``d`` coordinates ``mass_coordinates`` names: ``d = n`` joint rates
        (``"joint"``) or ``d = m`` pose-coordinate rates (``"task"``; a rotation vector's or tilt's
        rate, not the twist: ``kinematics.dynamics`` takes them to twists with
        ``coordinate_rates_to_twist``). The batch is flattened and last (``N`` poses).

        Parameters
        ----------
        q : array_like, shape (N, n)
            Actuated joints.
        x : array_like, shape (N, m)
            Their poses.

        Returns
        -------
        jv : ndarray, shape (k, 3, d, N), or list of k arrays (3, d, N)
            ``dc_b/du``: each centre of mass's velocity per unit coordinate rate, m/s per unit.
        jw : ndarray, shape (k, 3, d, N), or list of k arrays (3, d, N)
            ``dw_b/du``: each body's angular velocity (base frame), rad/s per unit.
        rotations : ndarray, shape (k, 3, 3, N), or list of k arrays (3, 3, N)
            Each body frame's orientation (its inertia tensor's axes).
        G : ndarray, shape (n, d, N), or None
            ``dq/dx`` of the actuated joints (task coordinates, for the rotors' ``G^T diag(J N^2) G``);
            ``None`` for joint coordinates.

        Raises
        ------
        ValueError
            Without a mass model.
        """
        ...

    def mass_matrix(self, q: ArrayLike, x: ArrayLike | None = None, *, rotors: bool = True) -> FloatArray:
        """Joint-space mass matrix ``M(q)`` (..., n, n), rotors' ``J_u N_u^2`` included unless ``rotors=False``.

        Parameters
        ----------
        q : array_like, shape (..., n)
        x : array_like, shape (..., m), optional
        rotors : bool

        Returns
        -------
        ndarray, shape (..., n, n)
            kg m^2 (revolute), kg (prismatic).

        Raises
        ------
        ValueError
            Without a mass model, or for redundant actuation (``n > m``: no ``M`` over dependent joints).
        """
        ...

    def task_inertia(self, q: ArrayLike, x: ArrayLike | None = None, *, rotors: bool = True) -> FloatArray:
        """Task-space inertia ``Lambda = (J M^-1 J^T)^-1`` (..., m, m), per twist (``coordinate_rates_to_twist``).

        Parameters
        ----------
        q : array_like, shape (..., n)
        x : array_like, shape (..., m), optional
        rotors : bool

        Returns
        -------
        ndarray, shape (..., m, m)
            kg on length rows and columns, kg m^2 on angles, kg m mixed.

        Raises
        ------
        ValueError
            Without a mass model.
        """
        ...

    def body_masses(self) -> FloatArray:
        """Mass of each moving body of the mass model, shape (k,), kg.

        Returns
        -------
        ndarray, shape (k,)
        """
        ...

    def centres_of_mass(self, q: ArrayLike) -> FloatArray:
        """Centre of mass of each body in the base frame, shape (..., k, 3), m.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.

        Returns
        -------
        ndarray, shape (..., k, 3)
        """
        ...

    def centres_of_mass_jacobian(self, q: ArrayLike) -> FloatArray:
        """``dp_i/dq`` of each centre of mass, shape (..., k, 3, n), m/rad (m/m prismatic).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.

        Returns
        -------
        ndarray, shape (..., k, 3, n)
        """
        ...

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike) -> FloatArray:
        """Gravitational potential energy ``-sum_i m_i g . p_i(q)`` (...), J.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        gravity : array_like, shape (3,)
            Gravity in the base frame, m/s^2.

        Returns
        -------
        ndarray, shape (...)
        """
        ...

    def gravity_torque(self, q: ArrayLike, gravity: ArrayLike) -> FloatArray:
        """Joint torque spent holding the links against ``gravity``, ``dV/dq``, shape (..., n), N m.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.
        gravity : array_like, shape (3,)
            Gravity in the base frame, m/s^2.

        Returns
        -------
        ndarray, shape (..., n)
            N m (N for a prismatic joint).
        """
        ...

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline through the links for drawing, shape (..., k, d) with ``d`` 2 or 3, m.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints.

        Returns
        -------
        ndarray, shape (..., k, d)
            Polyline vertices, m.
        """
        ...

    def replace(self, **changes: Any) -> Self:
        """A new model with some parameters (SI) changed, validated like the constructor.

        Parameters
        ----------
        **changes
            Parameter names and their new values, SI units.

        Returns
        -------
        Mechanism
            A new model of the same kind.
        """
        ...
