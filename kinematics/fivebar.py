"""Planar five-bar linkage (Singh, Saha, Manivannan, paper 002).

Base joints at ``(-a3, 0)`` and ``(a3, 0)``, proximal links ``a1``, distal links ``a2``,
both base joints actuated. Actuated angles ``q = (theta_1, theta_2)`` are measured from +x
towards +y; the end-effector ``C = (x, y)``.

Working modes (IK branches) are written ``"+-"``: the sign of the elbow offset of leg 1 and
leg 2. ``"+-"`` puts both elbows outwards, the usual haptic-device configuration. Assembly
modes (FK branches) are ``"up"`` (C to the left of B1 -> B2, i.e. above the elbows in the
usual pose) and ``"down"``.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, memoised
from .bodies import Body, body_arrays, columns, dot3, plane_link_part, point_mass, rod, stack_bodies, translating_part
from .mass_params import check_mass_params, link_frames, mass_param_info, planar, translating
from .validation import as_points, choice, optional_positive_vector, positive_finite, positive_vector

WORKING_MODES = ("+-", "++", "-+", "--")
ASSEMBLY_MODES = ("up", "down")
ACTUATORS = ("theta_1", "theta_2")
#: The mass model's links, uniform rods (``link_masses``); the handle is ``handle_mass``.
LINKS = ("proximal_1", "proximal_2", "distal_1", "distal_2")
#: ``joint_sensors``: the joint resolution is the device's, or its sensors are not modelled.
SENSORS = ("given", "none")
_DEG = np.pi / 180.0


#: Paper 002's dexterous annulus in normalised lengths: radii 0.9 L to 1.7 L about the base's
#: centre, ``L = (a1 + a2 + a3) / 3`` (its sec. 2 and 4.1).
DEXTEROUS_ANNULUS = (0.9, 1.7)


class Singularity(IntEnum):
    """Singularity class of a five-bar pose (paper 002, section 3.4)."""

    NONE = 0
    INVERSE = 1   # a leg fully stretched or folded: workspace boundary, J loses rank
    DIRECT = 2    # distal links aligned: the platform gains a DOF, J is unbounded
    COMBINED = 3  # both at once


@dataclass(frozen=True, slots=True)
class FiveBarParams:
    """Geometry (m), actuators and branch choice of a planar five-bar."""

    proximal: float = 0.10
    distal: float = 0.15
    half_base: float = 0.03
    motor_torques: tuple[float, float] = (0.1, 0.1)
    gear_ratios: tuple[float, float] = (1.0, 1.0)
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    working_mode: str = "+-"
    assembly_mode: str = "up"
    joint_limits: tuple[tuple[float, float], tuple[float, float]] | None = None
    #: |sin| of the link angles below which a pose is classed singular; ``None`` (default)
    #: derives it from eps and the link lengths (``FiveBar.singular_tolerance``).
    singular_tol: float | None = None
    #: One sensor count of each joint, joint side (rad), and whether it is the device's
    #: (``joint_sensors = "given"``) or its sensors are not modelled (``"none"``: no resolution).
    joint_resolution: tuple[float, float] = (360.0 / 4096 * _DEG,) * 2
    joint_sensors: str = "none"
    #: Mass model (``kinematics.mass_params``): each link a uniform rod of its length, kg; the
    #: handle a point mass at the end-effector, kg; rotor inertias motor side, kg m^2. The numbers
    #: are the paper 002 design's estimate (``resources/presets/fivebar_singh.toml``), off by default
    #: (``mass_model = "none"``): the paper gives no masses; the presets switch them on.
    link_masses: tuple[float, ...] = (0.0135, 0.0135, 0.02025, 0.02025)
    handle_mass: float = 0.02
    rotor_inertias: tuple[float, float] = (7e-06, 7e-06)
    mass_model: str = "none"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, ACTUATORS, scalars=("handle_mass",))
        set_(self, "proximal", positive_finite("proximal", self.proximal, "m"))
        set_(self, "distal", positive_finite("distal", self.distal, "m"))
        set_(self, "half_base", positive_finite("half_base", self.half_base, "m"))
        set_(self, "motor_torques", positive_vector("motor_torques", self.motor_torques, ACTUATORS, "N m"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ACTUATORS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ACTUATORS, "rad/s"))
        choice("working_mode", self.working_mode, WORKING_MODES)
        choice("assembly_mode", self.assembly_mode, ASSEMBLY_MODES)
        set_(self, "joint_resolution", positive_vector("joint_resolution", self.joint_resolution, ACTUATORS, "rad"))
        choice("joint_sensors", self.joint_sensors, SENSORS)
        if self.joint_limits is not None:
            limits = tuple(tuple(float(v) for v in pair) for pair in self.joint_limits)
            if len(limits) != 2 or any(len(p) != 2 or not p[0] < p[1] for p in limits):
                raise ValueError(
                    f"joint_limits must be ((lo1, hi1), (lo2, hi2)) in rad with lo < hi, got {self.joint_limits!r}"
                )
            set_(self, "joint_limits", limits)
        if self.singular_tol is not None:
            set_(self, "singular_tol", positive_finite("singular_tol", self.singular_tol))


class FiveBar(MechanismBase):
    """Planar five-bar: ``forward``, ``inverse``, ``jacobian``, singularity classes."""

    n_joints = 2
    task_dim = 2
    joint_names = ACTUATORS
    task_names = ("x", "y")
    #: ``Singularity`` names by code: ("none", "inverse", "direct", "combined").
    singularity_classes = tuple(s.name.lower() for s in Singularity)
    PARAM_INFO = (
        ParamInfo("proximal", "mm", 1e-3, "Proximal (driven) link length a1"),
        ParamInfo("distal", "mm", 1e-3, "Distal link length a2"),
        ParamInfo("half_base", "mm", 1e-3, "Half the distance between the base joints a3"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous motor torque", ACTUATORS),
        ParamInfo("gear_ratios", "", 1.0, "Transmission ratio, joint / motor", ACTUATORS),
        ParamInfo("working_mode", "", 1.0, "IK branch: elbow sign of leg 1 and leg 2", choices=WORKING_MODES),
        ParamInfo("assembly_mode", "", 1.0, "FK branch: end-effector above or below the elbows",
                  choices=ASSEMBLY_MODES),
        ParamInfo("joint_resolution", "deg", _DEG, "One encoder count of the joint (joint side)", ACTUATORS),
        ParamInfo("joint_sensors", "", 1.0, "joint_resolution is the device's (given) or not modelled (none)",
                  choices=SENSORS),
        *mass_param_info(LINKS, "uniform rods: proximal 1, 2, distal 1, 2", ACTUATORS),
        ParamInfo("handle_mass", "kg", 1.0, "Handle mass, a point at the end-effector"),
    )
    mass_coordinates = "task"

    def __init__(self, params: FiveBarParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else FiveBarParams(**kwargs))

    @property
    def dexterous_annulus(self) -> tuple[float, float]:
        """``(0.9 L, 1.7 L)``, ``L = (a1 + a2 + a3) / 3`` (``DEXTEROUS_ANNULUS``)."""
        p = self.params
        length = (p.proximal + p.distal + p.half_base) / 3.0
        return DEXTEROUS_ANNULUS[0] * length, DEXTEROUS_ANNULUS[1] * length

    # -- mass model -------------------------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """Four uniform rods (``LINKS``, x along the link from its base-side joint) and the handle."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        lengths = (p.proximal, p.proximal, p.distal, p.distal)
        return (*(rod(name, m, length) for name, m, length in zip(LINKS, p.link_masses, lengths)),
                point_mass("handle", p.handle_mass))

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame (the plane z = 0), (..., 5, 3, 3) and (..., 5, 3), m."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        q, x = as_points("q", q, 2), as_points("x", x, 2)
        q, x = np.broadcast_arrays(q, x)
        base = planar(np.broadcast_to(self._bases(), q.shape[:-1] + (2, 2)))
        elbow = planar(self.elbows(q))
        end = planar(x)
        normal = np.array([0.0, 0.0, 1.0])
        starts = [base[..., 0, :], base[..., 1, :], elbow[..., 0, :], elbow[..., 1, :]]
        ends = [elbow[..., 0, :], elbow[..., 1, :], end, end]
        rot = [link_frames(a, b, normal) for a, b in zip(starts, ends)] + [translating(q.shape[:-1])]
        return np.stack(rot, axis=-3), np.stack(starts + [end], axis=-2)

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (5, 3, 2, N), ``R_b`` (5, 3, 3, N), ``G = dq/dx`` (2, 2, N).

        Component-first (``kinematics.bodies``). ``G``'s row i is ``(C - B_i) / (a1 (C - B_i) . t_i)``,
        ``t_i = (-sin q_i, cos q_i)``: the loop closure ``|C - B_i| = a2`` differentiated; elbow i
        moves at ``a1 t_i G_i xdot``.
        """
        q, x = columns(as_points("q", q, 2).reshape(-1, 2)), columns(as_points("x", x, 2).reshape(-1, 2))
        n, a1 = q.shape[-1], self.params.proximal
        zero = np.zeros(n)
        bases = self._bases()
        elbows = [np.stack([bases[i, 0] + a1 * np.cos(q[i]), bases[i, 1] + a1 * np.sin(q[i]), zero]) for i in (0, 1)]
        tangents = [np.stack([-np.sin(q[i]), np.cos(q[i]), zero]) for i in (0, 1)]
        end = np.stack([x[0], x[1], zero])
        g = np.stack([(end[:2] - e[:2]) / (a1 * dot3(end - e, t)) for e, t in zip(elbows, tangents)])   # (2, 2, N)
        still = np.zeros((3, 2, n))
        delbows = [a1 * t[:, None] * g[i][None] for i, t in enumerate(tangents)]
        dend = np.zeros((3, 2, n))
        dend[0, 0] = dend[1, 1] = 1.0
        base = [np.stack([np.full(n, bases[i, 0]), np.full(n, bases[i, 1]), zero]) for i in (0, 1)]
        starts, ends = [*base, *elbows], [*elbows, end, end]
        dstarts, dends = [still, still, *delbows], [*delbows, dend, dend]
        normal = np.array([[0.0], [0.0], [1.0]])
        parts = [plane_link_part(a, e, normal, da, de) for a, e, da, de in zip(starts, ends, dstarts, dends)]
        jv, jw, rot = stack_bodies([*parts, translating_part(dend)], body_arrays(self.bodies())[1])
        return jv, jw, rot, g

    # -- geometry helpers ---------------------------------------------------------------
    def _bases(self) -> FloatArray:
        a3 = self.params.half_base
        return np.array([[-a3, 0.0], [a3, 0.0]])

    def elbows(self, q: ArrayLike) -> FloatArray:
        """Elbow points B1, B2 for joint angles ``q`` (..., 2), shape (..., 2, 2).

        Parameters
        ----------
        q : array_like, shape (..., 2)
            Actuated angles ``(theta_1, theta_2)``, rad.

        Returns
        -------
        ndarray, shape (..., 2, 2)
            Row i is elbow ``B_i``, m.

        Examples
        --------
        >>> FiveBar().elbows([np.pi / 2, np.pi / 2]).round(6).tolist()
        [[-0.03, 0.1], [0.03, 0.1]]
        """
        q = as_points("q", q, 2)
        a1 = self.params.proximal
        return self._bases() + a1 * np.stack([np.cos(q), np.sin(q)], axis=-1)

    # -- kinematics ---------------------------------------------------------------------
    def inverse(self, x: ArrayLike, working_mode: str | None = None) -> tuple[FloatArray, BoolArray]:
        """Actuated angles reaching ``x`` (..., 2) in the chosen working mode.

        Returns ``q`` (..., 2) and ``reachable`` (...). Unreachable points get ``nan``. A
        point within a few ulps outside the boundary (the cosine overshoots 1 by rounding) is
        clipped onto it rather than lost.

        Examples
        --------
        >>> q, ok = FiveBar().inverse([[0.0, 0.2], [0.0, 1.0]])
        >>> q.shape, ok.tolist()
        ((2, 2), [True, False])
        """
        mode = choice("working_mode", working_mode or self.params.working_mode, WORKING_MODES)
        x = as_points("x", x, 2)
        a1, a2 = self.params.proximal, self.params.distal
        signs = np.array([1.0 if mode[0] == "+" else -1.0, 1.0 if mode[1] == "+" else -1.0])
        d = x[..., None, :] - self._bases()                      # (..., 2 legs, 2)
        rho = np.hypot(d[..., 0], d[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_elbow = (a1 * a1 + rho * rho - a2 * a2) / (2.0 * a1 * rho)
        slack = 8 * np.finfo(float).eps
        ok = np.all(np.abs(cos_elbow) <= 1.0 + slack, axis=-1)
        offset = np.arccos(np.clip(cos_elbow, -1.0, 1.0))
        q = np.arctan2(d[..., 1], d[..., 0]) + signs * offset
        q = np.where(ok[..., None], q, np.nan)
        return q, ok

    def forward(self, q: ArrayLike, assembly_mode: str | None = None) -> tuple[FloatArray, BoolArray]:
        """End-effector ``x`` (..., 2) for angles ``q`` (..., 2), and whether it assembles.

        Examples
        --------
        >>> mech = FiveBar()
        >>> q, _ = mech.inverse([0.0, 0.2])
        >>> x, ok = mech.forward(q)
        >>> bool(np.allclose(x, [0.0, 0.2], rtol=0.0, atol=1e-12)), bool(ok)
        (True, True)
        """
        mode = choice("assembly_mode", assembly_mode or self.params.assembly_mode, ASSEMBLY_MODES)
        with np.errstate(invalid="ignore"):          # non-finite q: nan elbows, masked below
            b = self.elbows(q)
        b1, b2 = b[..., 0, :], b[..., 1, :]
        chord = b2 - b1
        half = 0.5 * np.hypot(chord[..., 0], chord[..., 1])
        height_sq = self.params.distal ** 2 - half * half
        ok = height_sq >= 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            unit = chord / (2.0 * half[..., None])
        normal = np.stack([-unit[..., 1], unit[..., 0]], axis=-1)   # +90 deg: left of B1 -> B2
        sign = 1.0 if mode == "up" else -1.0
        x = 0.5 * (b1 + b2) + sign * np.sqrt(np.maximum(height_sq, 0.0))[..., None] * normal
        return np.where(ok[..., None], x, np.nan), ok

    def _leg_vectors(self, q: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Distal link vectors ``C - B_i`` and proximal directions' derivatives, (..., 2, 2)."""
        b = self.elbows(q)
        distal = x[..., None, :] - b
        dtangent = np.stack([-np.sin(q), np.cos(q)], axis=-1)      # d/dtheta of (cos, sin)
        return distal, dtangent

    @property
    def singular_tolerance(self) -> float:
        """``|sin|`` of a link angle at or below which a pose is singular, derived from eps.

        ``params.singular_tol`` overrides it. Otherwise ``tol = sqrt(16 eps S)`` with
        ``S = max(S_leg, S_dir)``, the largest ``|sin|^2 / eps`` that rounding alone can give
        at an exactly singular pose (a1, a2, a3 the link lengths, ``r = a1 + a2`` the reach):

        - Inverse (leg i stretched or folded). ``inverse`` finds the angle at the base from
          ``c = (a1^2 + rho^2 - a2^2) / (2 a1 rho)``, ``rho = |C - O_i|``; counting roundings
          (``rho`` to 2 ulps, the squares, sums and the quotient) bounds its error by
          ``dc <= 5.5 eps (a1^2 + rho^2 + a2^2) / (2 a1 rho)``. Near ``c = 1`` the angle is
          ``sqrt(2 (1 - c))``, so an exactly singular point can come back ``sqrt(2 dc)`` off,
          and the elbow's ``|sin| = (rho / a2) sin(base angle)`` (law of sines) up to
          ``sin^2 <= 5.5 eps rho (a1^2 + rho^2 + a2^2) / (a1 a2^2)``; with ``rho <= r``:
          ``S_leg = r (r^2 + a1^2 + a2^2) / (a1 a2^2)``.
        - Direct (distal links aligned). ``forward`` puts C at height
          ``h = sqrt(a2^2 - half^2)`` above the elbows' midpoint, with ``half`` half the elbow
          distance; rounding of ``a2^2 - half^2`` is ``<= eps (1.5 a2^2 + 4 a2 (a1 + a3))``, and
          ``|sin| = 2 h half / a2^2 <= 2 h / a2``, so ``sin^2 <= 6 eps (1 + 3 (a1 + a3) / a2)``:
          ``S_dir = 1 + 3 (a1 + a3) / a2``.

        The factor 16 covers the counted constants (5.5 and 6) about three times over. Both
        bounds are square roots of eps because both singularities are fold points: a pose
        within rounding (``~eps r``) of the singular set has ``|sin| ~ sqrt(eps)``. For the
        paper 002 design (100, 150, 30 mm) ``tol = 1.9e-7``; the condition number of a pose
        this close to a singularity is above ``1 / tol ~ 5e6``.

        Returns
        -------
        float
            Dimensionless (a sine).

        Examples
        --------
        >>> f"{FiveBar(proximal=0.10, distal=0.15, half_base=0.03).singular_tolerance:.1e}"
        '1.9e-07'
        """
        if self.params.singular_tol is not None:
            return self.params.singular_tol
        a1, a2, a3 = self.params.proximal, self.params.distal, self.params.half_base
        reach = a1 + a2
        s_leg = reach * (reach * reach + a1 * a1 + a2 * a2) / (a1 * a2 * a2)
        s_dir = 1.0 + 3.0 * (a1 + a3) / a2
        return float(np.sqrt(16.0 * np.finfo(float).eps * max(s_leg, s_dir)))

    def _singular_parts(
        self, distal: FloatArray, dtangent: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoolArray, BoolArray]:
        """``jtheta`` (..., 2), ``det J_p`` (...), and the masks of singular legs (..., 2) and of a
        direct singularity (...).

        ``jtheta_i = a1 (C - B_i) . (-sin q_i, cos q_i) = a1 a2 sin(leg i's elbow angle)`` and
        ``det J_p = (C - B_1) x (C - B_2) = a2^2 sin(angle between the distal links)``.
        """
        a1, a2 = self.params.proximal, self.params.distal
        jtheta = a1 * np.sum(distal * dtangent, axis=-1)
        p = distal
        det = p[..., 0, 0] * p[..., 1, 1] - p[..., 0, 1] * p[..., 1, 0]
        tol = self.singular_tolerance
        with np.errstate(invalid="ignore"):      # nan poses are singular in no class
            legs = np.abs(jtheta) <= tol * a1 * a2
            direct = np.abs(det) <= tol * a2 * a2
        return jtheta, det, legs, direct

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., 2, 2) with ``xdot = J qdot``: ``J = J_p^-1 J_theta`` (paper 002 eq. 5 inverted).

        Differentiating ``|C - B_i|^2 = a2^2`` gives ``J_p xdot = J_theta qdot`` with rows
        ``J_p[i] = (C - B_i)`` and ``J_theta = diag(a1 (C - B_i) . (-sin q_i, cos q_i))``.
        The 2 x 2 inverse is written out (adjugate / determinant).

        Where ``singularity`` classes the pose singular, J takes its exact singular value
        instead of rounding noise: a singular leg's ``J_theta`` entry is 0, so its column is
        exactly zero (inverse singularity; both legs: ``J = 0``), and at a direct singularity
        (``det J_p = 0``) every entry is ``inf``. Every metric computed from J (condition
        number, facet distances, ellipsoids, anisotropic force) then takes its singular limit,
        in a map and a pose alike.

        Examples
        --------
        >>> mech = FiveBar()
        >>> q, _ = mech.inverse([[0.0, 0.2], [0.05, 0.15]])
        >>> mech.jacobian(q).shape
        (2, 2, 2)
        """
        q = as_points("q", q, 2)
        if x is None:
            x, _ = self.forward(q)
        distal, dtangent = self._leg_vectors(q, np.asarray(x, float))
        jtheta, det, legs, direct = self._singular_parts(distal, dtangent)
        jtheta = np.where(legs, 0.0, jtheta)
        p = distal
        adj = np.stack(
            [np.stack([p[..., 1, 1], -p[..., 0, 1]], -1), np.stack([-p[..., 1, 0], p[..., 0, 0]], -1)], -2
        )
        with np.errstate(divide="ignore", invalid="ignore"):
            jac = adj * jtheta[..., None, :] / det[..., None, None]
        return np.where(direct[..., None, None], np.inf, jac + 0.0)     # + 0.0: no -0 entries

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Which legs are stretched or folded (inverse singularity), shape (..., 2).

        Both at once (``|C - O_i|`` at ``a1 + a2`` or ``|a1 - a2|`` for both legs) is a double
        inverse singularity: still class ``INVERSE``, with ``J = 0``.
        """
        q = as_points("q", q, 2)
        if x is None:
            x, _ = self.forward(q)
        return self._singular_parts(*self._leg_vectors(q, np.asarray(x, float)))[2]

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """Singularity class (``Singularity`` values as int8) of each pose, shape (...).

        Inverse: ``|sin|`` of the angle between a proximal and its distal link (of either leg)
        at most ``singular_tolerance``. Direct: the same for the angle between the two distal
        links. ``singular_tolerance`` says how it follows from eps and the link lengths.

        Examples
        --------
        >>> mech = FiveBar()
        >>> q, _ = mech.inverse([0.0, 0.2])
        >>> int(mech.singularity(q))
        0
        """
        q = as_points("q", q, 2)
        if x is None:
            x, _ = self.forward(q)
        _, _, legs, direct = self._singular_parts(*self._leg_vectors(q, np.asarray(x, float)))
        inverse = np.any(legs, axis=-1)
        return (inverse * Singularity.INVERSE + direct * Singularity.DIRECT).astype(np.int8)

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Whether ``q`` (..., 2) is finite and inside the joint limits (if any)."""
        q = as_points("q", q, 2)
        ok = np.all(np.isfinite(q), axis=-1)
        if self.params.joint_limits is not None:
            for i, (lo, hi) in enumerate(self.params.joint_limits):
                with np.errstate(invalid="ignore"):
                    ok &= (q[..., i] >= lo) & (q[..., i] <= hi)
        return ok

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline base1 -> B1 -> C -> B2 -> base2 for drawing, shape (..., 5, 2)."""
        q = as_points("q", q, 2)
        b = self.elbows(q)
        x, _ = self.forward(q)
        base = np.broadcast_to(self._bases(), b.shape)
        return np.stack([base[..., 0, :], b[..., 0, :], x, b[..., 1, :], base[..., 1, :]], axis=-2)

    def singular_loci(self, samples: int = 720) -> dict[str, FloatArray]:
        """Task points just inside the reach where this five-bar approaches its inverse singularities.

        Leg ``i`` is stretched or folded where ``|C - O_i|`` is ``a1 + a2`` or ``|a1 - a2|``:
        two circles per base joint. ``"inverse"`` holds ``samples`` points on each circle,
        moved into the annulus by ``1e-9`` of the link scale (a point exactly on it is
        reachable or not by rounding); ``"all_inverse"`` the points where a circle of one
        base meets a circle of the other (both legs singular at once, J -> 0), moved into both
        annuli along the bisector of their inward normals by ``1e-7`` of the link scale.
        The caller keeps the points that are feasible and inside its domain: if one is, the
        feasible set's closure holds that singularity. Shapes (k, 2), m.

        Examples
        --------
        >>> loci = FiveBar().singular_loci(samples=8)
        >>> sorted(loci), loci["inverse"].shape
        (['all_inverse', 'inverse'], (32, 2))
        """
        a1, a2 = self.params.proximal, self.params.distal
        bases = self._bases()
        scale = a1 + a2
        radii = [(a1 + a2, -1.0)] + ([(abs(a1 - a2), 1.0)] if a1 != a2 else [])   # (radius, outward sign)
        angle = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
        ring = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
        inverse = [base + (r + sign * 1e-9 * scale) * ring for base in bases for r, sign in radii]
        corners = []
        for r1, s1 in radii:
            for r2, s2 in radii:
                # Circles |C - O_1| = r1, |C - O_2| = r2 with O_i = (-+a3, 0) meet at x = (r1^2 - r2^2) / (4 a3).
                x = (r1 * r1 - r2 * r2) / (4.0 * self.params.half_base)
                y_sq = r1 * r1 - (x - bases[0, 0]) ** 2
                if y_sq < 0.0:
                    continue
                for y in (np.sqrt(y_sq), -np.sqrt(y_sq)):
                    point = np.array([x, y])
                    n1 = (point - bases[0]) / r1 * s1        # direction into annulus 1
                    n2 = (point - bases[1]) / r2 * s2
                    step = n1 + n2
                    length = np.hypot(*step)
                    if length > 0.0:
                        corners.append(point + 1e-7 * scale * step / length)
        return {"inverse": np.concatenate(inverse), "all_inverse": np.array(corners).reshape(-1, 2)}

    def max_inscribed_circle(self) -> tuple[float, float]:
        """Centre height ``y_MIC`` and radius ``r_MIC`` (m) of the maximum inscribed circle.

        Paper 002 (section 5) defines the MIC as the circle centred on the y axis tangent to
        the workspace boundary. Each leg reaches the annulus ``|a1 - a2| <= |C - O_i| <= a1 + a2``,
        so the circle has radius ``(a1 + a2 - |a1 - a2|) / 2 = min(a1, a2)`` (as printed) and
        its centre lies at distance ``(a1 + a2 + |a1 - a2|) / 2 = max(a1, a2)`` from both base
        joints: ``y = sqrt(max(a1, a2)^2 - a3^2)``. The machine-read text prints
        ``sqrt(r^2 / 4 - (a3 / 2)^2)`` there, which is not tangent to both annulus circles, so
        we use the geometric value. ``nan`` centre where ``a3 > max(a1, a2)``.

        Returns
        -------
        y_mic : float
            Centre height on the y axis, m (``nan`` where ``a3 > max(a1, a2)``).
        r_mic : float
            Radius, m.

        Examples
        --------
        >>> y, r = FiveBar(proximal=0.10, distal=0.15, half_base=0.03).max_inscribed_circle()
        >>> round(y, 6), r
        (0.146969, 0.1)
        """
        a1, a2, a3 = self.params.proximal, self.params.distal, self.params.half_base
        radius = 0.5 * (a1 + a2 - abs(a1 - a2))
        centre_dist = 0.5 * (a1 + a2 + abs(a1 - a2))
        y_sq = centre_dist * centre_dist - a3 * a3
        return (float(np.sqrt(y_sq)) if y_sq >= 0 else float("nan")), radius
