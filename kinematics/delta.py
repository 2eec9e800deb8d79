"""Delta-type parallel positioner: three rotary arms, parallelogram forearms, a translating platform.

One module over the ~600-line guide on purpose: the forward and inverse kinematics, the
Jacobian, the singular classes and the body frames follow one source (``libnifalcon``) line by
line with its conventions, which a reader checks against that source in one place.

The Novint Falcon (and the Force Dimension delta.3 / omega.3 type). The model follows
``libnifalcon`` (``src/kinematic/FalconKinematicStamper.cpp``, after R. E. Stamper's thesis),
with every length and angle a parameter:

* Base frame: ``z`` points out of the device towards the user, ``x``/``y`` span the base.
  Leg ``i`` has the azimuth ``phi_i = (90, -30, -150) deg + arm_offset_angle`` (the Falcon's
  legs are turned 15 deg about ``z``: ``OFFSET_ANGLE`` in ``FalconGeometry.h``) and the leg
  frame ``u_i = (cos phi_i, sin phi_i, 0)`` (radial), ``v_i = (-sin phi_i, cos phi_i, 0)``
  (along the motor axis), ``w = z``.
* The arm (``upper_arm`` ``a``) turns about the axis through ``base_radius u_i + base_offset_v
  v_i`` (``r``, ``s``) parallel to ``v_i``; its angle ``q_i`` (libnifalcon's ``theta1``) is
  measured in the ``u``-``w`` plane from ``u_i`` towards ``+z``. Knee:
  ``k_i = r u + s v + a (cos q u + sin q w)``.
* The forearm: a knee hinge parallel to ``v`` (angle ``theta2``), an offset ``knee_offset``
  ``e``, the parallelogram of bars ``parallelogram`` ``b`` at the angle ``theta3`` from ``v``,
  an offset ``platform_joint_offset`` ``d``, and the platform point ``x`` at
  ``-platform_offset_u u - platform_offset_v v`` (``c``, ``f``) from the forearm's end.
  With ``Q_i = x + c u + f v - k_i``, ``rho = |Q_i - (Q_i . v) v|`` and ``D = d + e``:
  ``Q . v = b cos theta3`` and ``rho = D + b sin theta3`` (libnifalcon's IK). The platform
  point of each leg lies on a torus about the knee (tube radius ``b``, ring radius ``D``),
  not on a sphere: with ``D = 0`` it is the classical delta's sphere.

Inverse kinematics (closed form per arm, libnifalcon's branch): ``theta3 = acos(Q_v / b)`` in
``[0, pi]``, then the arm angle is the circle-circle intersection in the leg's ``u``-``w``
plane, ``q = atan2(P_w, P_u + c - r) - acos((rho^2 + a^2 - L^2) / (2 a rho))`` with ``L = D + b
sin theta3`` (the knee bends outwards; libnifalcon's ``T1b`` root of its half-angle quadratic).

Forward kinematics: each torus is replaced by the sphere of radius ``b`` about its nearest
ring point ``C_i = k_i - c u - f v + D (Q_i - Q_v v) / rho``; three equal spheres meet on the
normal through their circumcentre (closed form, the root in front of the knees, ``+z`` side
of the plane of the three centres). A fixed-point iteration on the ring points (each step
contracts the error by about ``D / rho``) then a Newton polish on the exact torus residuals
finds ``x``; ``ok`` is False where the spheres do not meet, the centres are collinear, the
iteration does not converge, or the answer is on the inner half of a torus (``sin theta3 <
0``, not libnifalcon's branch).

Jacobian: differentiating ``|x - C_i| = b`` (the ring point's motion is perpendicular to the
bar ``n_i = x - C_i``) gives ``n_i . xdot = n_i . (dk_i/dq_i) qdot_i``: ``A xdot = B qdot``
with rows ``n_i`` and ``B = diag(n_i . dk_i/dq_i)``, so ``J = A^-1 B`` (``xdot = J qdot``),
statics ``tau = J^T f`` (libnifalcon's ``getForces``: ``torque = J^T force``). ``B_ii = 0`` is
an inverse (boundary) singularity of arm ``i`` (arm and bar in line); ``det A = 0`` a direct one.

Limits: arm angle ``[arm_lower, arm_upper]``, knee bend ``theta2 - q`` in ``[knee_min,
knee_max]`` (0: arm and forearm's projection in line), bar angle ``|theta3 - 90 deg| <=
bar_limit``. None of these is published for the Falcon; the defaults are estimates
(``resources/presets/novint_falcon.toml`` says so).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import delta_loci
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, memoised, singular_limit
from .bodies import (
    Body,
    body_arrays,
    columns,
    dot3,
    link_part,
    point_mass,
    rod,
    stack_bodies,
    translating_part,
    unit_rate,
)
from .mass_params import check_mass_params, link_frames, mass_param_info, translating
from .rotations import angle_in, batched_inverse, finite_rows
from .validation import as_points, choice, optional_positive_vector, positive_finite, positive_vector

ARMS = ("q1", "q2", "q3")
#: The mass model's rods (``link_masses``): each leg's arm, then each leg's pair of parallelogram
#: bars (one rod along the parallelogram's centre line, the pair's mass); the platform with its
#: grip is ``platform_mass``.
LINKS = ("arm_1", "arm_2", "arm_3", "bars_1", "bars_2", "bars_3")
#: ``joint_sensors``: the joint resolution is the device's, or its sensors are not modelled.
SENSORS = ("given", "none")
_DEG = np.pi / 180.0
_EPS = np.finfo(np.float64).eps
#: Leg azimuths before ``arm_offset_angle`` (libnifalcon ``phy``: pi/2, -pi/6, -5 pi/6).
_AZIMUTHS = np.array([90.0, -30.0, -150.0]) * _DEG
#: Fixed-point sweeps over the ring points before Newton (each contracts by ~ D / rho).
_FIXED_POINT_STEPS = 6
#: Newton steps on the torus residuals; quadratic convergence needs 2-3 from the fixed point.
_NEWTON_STEPS = 8
#: FK tolerance on the residual ``|x - C_i| - b``, relative to the device size ``S``. Each residual
#: is a few additions and a 3-norm of vectors bounded by ``S`` (about ``10 u S``, ``u = eps/2``), and
#: the stored iterate itself rounds by ``sqrt(3) u S``; 32 eps (about three times that) is attainable
#: on every SIMD path and still 4e-15 m for the Falcon (S ~ 0.25 m).
FK_RTOL = 32 * _EPS


def _finite(name: str, value, unit: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        out = np.nan
    if isinstance(value, bool) or not np.isfinite(out):
        raise ValueError(f"{name} must be a finite number in {unit}, got {value!r}")
    return out


@dataclass(frozen=True, slots=True)
class DeltaParams:
    """Geometry (m, rad), limits (rad) and actuators (N m, ratio) of a delta positioner.

    Defaults: the Novint Falcon after libnifalcon's ``FalconGeometry.h`` (``a, b, c, d, e, f,
    r, s`` and the 15 deg ``OFFSET_ANGLE``); capstan ratio ``SMALL_ARM_DIAMETER /
    SHAFT_DIAMETER = 0.110 / 0.01425``; the limits and the motor torque are estimates (see the
    preset).
    """

    upper_arm: float = 0.060
    parallelogram: float = 0.1025
    knee_offset: float = 0.01125
    platform_joint_offset: float = 0.01125
    platform_offset_u: float = 0.01443
    platform_offset_v: float = -0.025
    base_radius: float = 0.040
    base_offset_v: float = -0.02309
    arm_offset_angle: float = 15 * _DEG
    arm_lower: float = -60 * _DEG
    arm_upper: float = 110 * _DEG
    knee_min: float = 10 * _DEG
    knee_max: float = 170 * _DEG
    bar_limit: float = 50 * _DEG
    motor_torques: tuple[float, ...] = (0.05306,) * 3
    gear_ratios: tuple[float, ...] = (0.110 / 0.01425,) * 3
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    #: One sensor count of each joint, joint side (rad), and whether it is the device's
    #: (``joint_sensors = "given"``) or its sensors are not modelled (``"none"``: no resolution).
    joint_resolution: tuple[float, ...] = (360.0 * 0.01425 / (4 * 320 * 0.110) * _DEG,) * 3
    joint_sensors: str = "given"
    #: Mass model (``kinematics.mass_params``): uniform rods (arms from the motor axis to the knee,
    #: bar pairs along the parallelogram), the platform and grip a point at ``x``, rotor inertias
    #: motor side. Estimates (``resources/presets/novint_falcon.toml``), off by default.
    link_masses: tuple[float, ...] = (0.015, 0.015, 0.015, 0.008, 0.008, 0.008)
    platform_mass: float = 0.06
    rotor_inertias: tuple[float, ...] = (1e-6, 1e-6, 1e-6)
    mass_model: str = "none"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, ARMS, scalars=("platform_mass",))
        for name in ("upper_arm", "parallelogram"):
            set_(self, name, positive_finite(name, getattr(self, name), "m"))
        for name in ("platform_offset_u", "platform_offset_v", "base_radius", "base_offset_v"):
            set_(self, name, _finite(name, getattr(self, name), "m"))
        for name in ("knee_offset", "platform_joint_offset"):
            value = _finite(name, getattr(self, name), "m")
            if value < 0:
                raise ValueError(f"{name} must be >= 0 m, got {value!r}")
            set_(self, name, value)
        set_(self, "arm_offset_angle", angle_in("arm_offset_angle", self.arm_offset_angle, -np.pi, np.pi))
        set_(self, "arm_lower", angle_in("arm_lower", self.arm_lower, -np.pi, np.pi))
        set_(self, "arm_upper", angle_in("arm_upper", self.arm_upper, -np.pi, np.pi))
        if not self.arm_lower < self.arm_upper:
            raise ValueError(f"arm_lower must be below arm_upper, got {self.arm_lower} >= {self.arm_upper} rad")
        set_(self, "knee_min", angle_in("knee_min", self.knee_min, 0.0, np.pi))
        set_(self, "knee_max", angle_in("knee_max", self.knee_max, 0.0, np.pi, open_lower=True))
        if not self.knee_min < self.knee_max:
            raise ValueError(f"knee_min must be below knee_max, got {self.knee_min} >= {self.knee_max} rad")
        set_(self, "bar_limit", angle_in("bar_limit", self.bar_limit, 0.0, np.pi / 2, open_lower=True))
        set_(self, "motor_torques", positive_vector("motor_torques", self.motor_torques, ARMS, "N m"))
        set_(self, "joint_resolution", positive_vector("joint_resolution", self.joint_resolution, ARMS, "rad"))
        choice("joint_sensors", self.joint_sensors, SENSORS)
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ARMS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ARMS, "rad/s"))


def _along(x: FloatArray, axes: FloatArray) -> FloatArray:
    """``x @ axes.T`` (..., 3), formed term by term: ``x_0 a_0 + x_1 a_1 + x_2 a_2``.

    A point's bits then do not depend on the batch it came in (a BLAS matmul rounds a lone row
    otherwise than a block of rows: the feasible set moved with the chunking), and the compiled
    kernel (``metrics.kernels.delta``) forms the same sums.
    """
    return x[..., 0:1] * axes[:, 0] + x[..., 1:2] * axes[:, 1] + x[..., 2:3] * axes[:, 2]


def _circumcentre(c1: FloatArray, c2: FloatArray, c3: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Circumcentre (..., 3), unit normal (..., 3) with ``n_z >= 0`` and squared circumradius (...).

    Collinear or coincident centres give ``nan`` (no warning).
    """
    p, r = c1 - c3, c2 - c3
    n = np.cross(p, r)
    nn = np.sum(n * n, axis=-1)
    good = nn > 0
    safe = np.where(good, nn, 1.0)
    pp, rr = np.sum(p * p, -1), np.sum(r * r, -1)
    off = np.cross(pp[..., None] * r - rr[..., None] * p, n) / (2 * safe[..., None])
    unit = n / np.sqrt(safe)[..., None]
    unit = np.where((unit[..., 2:3] < 0), -unit, unit)
    off = np.where(good[..., None], off, np.nan)
    return c3 + off, np.where(good[..., None], unit, np.nan), np.where(good, np.sum(off * off, -1), np.nan)


class Delta(MechanismBase):
    """Delta positioner (Novint Falcon defaults): ``q`` = arm angles (rad), ``x`` = platform point (m)."""

    n_joints = 3
    task_dim = 3
    joint_names = ARMS
    task_names = ("x", "y", "z")
    singularity_classes = ("none", "inverse", "direct")
    PARAM_INFO = (
        ParamInfo("upper_arm", "mm", 1e-3, "Arm length, motor axis to knee (libnifalcon a)"),
        ParamInfo("parallelogram", "mm", 1e-3, "Parallelogram bar length (libnifalcon b)"),
        ParamInfo("knee_offset", "mm", 1e-3, "Knee hinge to parallelogram (libnifalcon e)"),
        ParamInfo("platform_joint_offset", "mm", 1e-3, "Parallelogram to platform hinge (libnifalcon d)"),
        ParamInfo("platform_offset_u", "mm", 1e-3, "Platform hinge to centre, radial (libnifalcon c)"),
        ParamInfo("platform_offset_v", "mm", 1e-3, "Platform hinge to centre, along the motor axis (libnifalcon f)"),
        ParamInfo("base_radius", "mm", 1e-3, "Centre to motor axis, radial (libnifalcon r)"),
        ParamInfo("base_offset_v", "mm", 1e-3, "Centre to arm plane, along the motor axis (libnifalcon s)"),
        ParamInfo("arm_offset_angle", "deg", _DEG, "Turn of the three legs about z (Falcon 15 deg)"),
        ParamInfo("arm_lower", "deg", _DEG, "Lowest arm angle"),
        ParamInfo("arm_upper", "deg", _DEG, "Highest arm angle"),
        ParamInfo("knee_min", "deg", _DEG, "Smallest knee bend (forearm from the arm's line)"),
        ParamInfo("knee_max", "deg", _DEG, "Largest knee bend"),
        ParamInfo("bar_limit", "deg", _DEG, "Largest parallelogram swing from square"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous motor torque", ARMS),
        ParamInfo("gear_ratios", "", 1.0, "Capstan ratio, arm drum to motor shaft", ARMS),
        ParamInfo("joint_resolution", "deg", _DEG, "One encoder count of the arm (joint side)", ARMS),
        ParamInfo("joint_sensors", "", 1.0, "joint_resolution is the device's (given) or not modelled (none)",
                  choices=SENSORS),
        *mass_param_info(LINKS, "uniform rods: arms 1-3, parallelogram bar pairs 1-3", ARMS),
        ParamInfo("platform_mass", "kg", 1.0, "Platform and grip mass, a point at the platform centre"),
    )
    mass_coordinates = "task"

    def __init__(self, params: DeltaParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else DeltaParams(**kwargs))

    # -- mass model -------------------------------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """Three arms and three bar pairs (uniform rods along body x) and the platform point."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        lengths = (p.upper_arm,) * 3 + (p.parallelogram,) * 3
        return (*(rod(name, m, length) for name, m, length in zip(LINKS, p.link_masses, lengths)),
                point_mass("platform", p.platform_mass))

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame, (..., 7, 3, 3) and (..., 7, 3), m.

        Arm i from its motor-axis point to its knee (turning about ``v_i``); bar pair i from the
        parallelogram's knee end to its platform end (``_leg_points``, as ``link_points`` draws it).
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        q, x = as_points("q", q, 3), as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        base, knee, top, end = self._leg_points(q, x)
        _, v = self.leg_frames()
        rot = [link_frames(base[..., i, :], knee[..., i, :], v[i]) for i in range(3)]
        rot += [link_frames(top[..., i, :], end[..., i, :], v[i]) for i in range(3)]
        rot.append(translating(x.shape[:-1]))
        origins = [base[..., i, :] for i in range(3)] + [top[..., i, :] for i in range(3)] + [x]
        return np.stack(rot, axis=-3), np.stack(origins, axis=-2)

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (7, 3, 3, N), ``R_b`` (7, 3, 3, N) and ``G = dq/dx`` (3, 3, N).

        Component-first (``kinematics.bodies``). The loop closure of leg i (its bar ``n_i`` of fixed
        length) gives ``qdot_i = n_i . xdot / (n_i . dK_i/dq_i)``: ``G``'s row i. The knee moves at
        ``dK_i/dq_i G_i``; the parallelogram's ends follow the unit radial ``perp / rho`` of
        ``x - K_i`` across the motor axis ``v_i`` (``_leg_points``), differentiated in closed form.
        """
        q, x = as_points("q", q, 3).reshape(-1, 3), as_points("x", x, 3).reshape(-1, 3)
        p = self.params
        knee_eff, dknee = self._knees(q)
        bar, _, _ = self._bars(x, knee_eff)
        base, knee, top, end = (columns(a) for a in self._leg_points(q, x))             # (3 legs, 3, N)
        knee_eff, dknee, bar, x = columns(knee_eff), columns(dknee), columns(bar), columns(x)
        n = x.shape[-1]
        g = bar / dot3(np.swapaxes(bar, 0, 1), np.swapaxes(dknee, 0, 1))[:, None]       # (3, 3, N)
        _, v = self.leg_frames()
        dx = np.zeros((3, 3, n))
        dx[0, 0] = dx[1, 1] = dx[2, 2] = 1.0
        still = np.zeros((3, 3, n))
        arms, bars = [], []
        for i in range(3):
            vi = v[i][:, None]
            dk = dknee[i][:, None] * g[i][None]                                            # (3, d, N)
            qv = x - knee_eff[i]
            dqv = dx - dk
            perp = qv - vi * dot3(qv, vi)
            dperp = dqv - vi[:, None] * dot3(dqv, vi[:, None])
            rho = np.sqrt(dot3(perp, perp))
            dradial = unit_rate(perp / rho, dperp, rho)
            dtop = dk + p.knee_offset * dradial
            dend = dx - p.platform_joint_offset * dradial       # end = x + offsets - (D - knee_offset) radial
            arms.append(link_part(base[i], knee[i], vi, still, dk))
            bars.append(link_part(top[i], end[i], vi, dtop, dend))
        jv, jw, rot = stack_bodies([*arms, *bars, translating_part(dx)], body_arrays(self.bodies())[1])
        return jv, jw, rot, g

    def _leg_points(self, q: FloatArray, x: FloatArray) -> tuple[FloatArray, ...]:
        """Motor-axis point, knee, and the parallelogram's two ends of each leg, each (..., 3, 3)."""
        p = self.params
        u, v = self.leg_frames()
        knee_eff, _ = self._knees(q)
        knee = knee_eff + p.platform_offset_u * u + p.platform_offset_v * v
        bar, _, _ = self._bars(x, knee_eff)
        qv = x[..., None, :] - knee_eff
        perp = qv - np.sum(qv * v, -1)[..., None] * v
        rho = np.linalg.norm(perp, axis=-1)
        radial = perp / np.where(rho > 0, rho, 1.0)[..., None]
        top = knee + p.knee_offset * radial
        base = np.broadcast_to(p.base_radius * u + p.base_offset_v * v, knee.shape)
        return base, knee, top, top + bar

    # -- geometry ---------------------------------------------------------------------------
    def azimuths(self) -> FloatArray:
        """Leg azimuths ``phi_i`` about ``z``, (3,), rad.

        Returns
        -------
        ndarray, shape (3,)
        """
        return _AZIMUTHS + self.params.arm_offset_angle

    def leg_frames(self) -> tuple[FloatArray, FloatArray]:
        """Radial ``u_i`` and motor-axis ``v_i`` unit vectors of each leg, each (3, 3) (row i), base frame.

        Returns
        -------
        u, v : ndarray, shape (3, 3)
        """
        phi = self.azimuths()
        c, s, z = np.cos(phi), np.sin(phi), np.zeros(3)
        return np.stack([c, s, z], -1), np.stack([-s, c, z], -1)

    def _knees(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Effective knee ``K_i = k_i - c u - f v`` (..., 3, 3) and ``dK_i/dq_i`` (..., 3, 3)."""
        p = self.params
        u, v = self.leg_frames()
        w = np.array([0.0, 0.0, 1.0])
        cq, sq = np.cos(q)[..., None], np.sin(q)[..., None]
        root = (p.base_radius - p.platform_offset_u) * u + (p.base_offset_v - p.platform_offset_v) * v
        knee = root + p.upper_arm * (cq * u + sq * w)
        dknee = p.upper_arm * (-sq * u + cq * w)
        return knee, dknee

    def _bars(self, x: FloatArray, knee: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Bar vectors ``n_i = x - C_i`` (..., 3, 3), ``Q . v`` and ``rho - D`` (..., 3) of each leg."""
        _, v = self.leg_frames()
        big_d = self.params.knee_offset + self.params.platform_joint_offset
        qv = x[..., None, :] - knee
        along = np.sum(qv * v, -1)
        perp = qv - along[..., None] * v
        rho = np.linalg.norm(perp, axis=-1)
        safe = np.where(rho > 0, rho, 1.0)
        bar = perp * ((rho - big_d) / safe)[..., None] + along[..., None] * v
        return bar, along, rho - big_d

    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """Lowest and highest arm angle, each (3,), rad.

        Returns
        -------
        lower, upper : ndarray, shape (3,)
        """
        return np.full(3, self.params.arm_lower), np.full(3, self.params.arm_upper)

    def home_pose(self) -> FloatArray:
        """Platform point (3,) with every arm at the middle of its range, m (the drawings' reference pose).

        Returns
        -------
        ndarray, shape (3,)
            ``nan`` if that pose does not assemble.
        """
        mid = 0.5 * (self.params.arm_lower + self.params.arm_upper)
        return self.forward(np.full(3, mid))[0]

    def size(self) -> float:
        """Device size ``S`` (m): the reach ``|r| + |s| + |c| + |f| + a + b + D`` (scale of FK tolerances).

        Returns
        -------
        float
        """
        p = self.params
        return (abs(p.base_radius) + abs(p.base_offset_v) + abs(p.platform_offset_u) + abs(p.platform_offset_v)
                + p.upper_arm + p.parallelogram + p.knee_offset + p.platform_joint_offset)

    # -- kinematics -------------------------------------------------------------------------
    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Arm angles ``q`` (..., 3) reaching platform points ``x`` (..., 3), closed form per arm."""
        x = as_points("x", x, 3)
        x, finite = finite_rows(x, [0.0, 0.0, 0.15])
        pu, pw, cos3, rho, _, k = self._reach_terms(x)
        ok3 = np.abs(cos3) <= 1.0
        ok1 = (rho > 0) & (np.abs(k) <= 1.0)
        q = np.arctan2(pw, pu) - np.arccos(np.clip(k, -1.0, 1.0))
        q = q - 2 * np.pi * np.floor((q + np.pi) / (2 * np.pi))
        ok = finite & np.all(ok3 & ok1, axis=-1)
        return np.where(ok[..., None], q, np.nan), ok

    def _reach_terms(self, x: FloatArray) -> tuple[FloatArray, ...]:
        """Per-leg IK terms of finite points ``x`` (..., 3), each (..., 3): ``P_u + c``, ``P_w``,
        ``cos theta3``, ``rho``, the forearm reach ``L = D + b sin theta3`` and
        ``k = (rho^2 + a^2 - L^2) / (2 a rho)``, the cosine of the arm's angle from the platform
        direction. Leg i reaches ``x`` where ``|cos theta3| <= 1`` and ``|k| <= 1``; ``k = +-1`` is its
        knee stretched or folded and ``cos theta3 = +-1`` its bars along the motor axis (the inverse
        singularities)."""
        p = self.params
        u, v = self.leg_frames()
        big_d = p.knee_offset + p.platform_joint_offset
        pu = _along(x, u) - p.base_radius + p.platform_offset_u   # (..., 3): P_u + c
        pv = _along(x, v) - p.base_offset_v + p.platform_offset_v  # P_v + f = b cos theta3
        pw = x[..., 2:3] + np.zeros(3)
        cos3 = pv / p.parallelogram
        sin3 = np.sqrt(np.clip(1.0 - cos3 * cos3, 0.0, None))
        reach = big_d + p.parallelogram * sin3                    # L
        rho = np.hypot(pu, pw)
        safe = np.where(rho > 0, rho, 1.0)
        k = (rho * rho + p.upper_arm ** 2 - reach * reach) / (2 * p.upper_arm * safe)
        return pu, pw, cos3, rho, reach, k

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Platform point ``x`` (..., 3) of arm angles ``q`` (..., 3): sphere intersection, then Newton."""
        p = self.params
        q = as_points("q", q, 3)
        q, finite = finite_rows(q, [0.3, 0.3, 0.3])
        knee, _ = self._knees(q)
        big_d = p.knee_offset + p.platform_joint_offset
        b = p.parallelogram
        # Start: the knees' centroid pushed forward (+z) by the forearm's reach.
        start = np.mean(knee, axis=-2) + np.array([0.0, 0.0, b + big_d])
        x = start
        ok = finite.copy()
        for _ in range(_FIXED_POINT_STEPS):
            bar, _, _ = self._bars(x, knee)
            x, good = self._meet(x[..., None, :] - bar, b)     # ring points C_i = x - n_i
            ok &= good
            x = np.where(good[..., None], x, start)
        for _ in range(_NEWTON_STEPS):
            bar, _, _ = self._bars(x, knee)
            length = np.linalg.norm(bar, axis=-1)
            res = length - b
            grad = bar / np.where(length > 0, length, 1.0)[..., None]
            inv, good = batched_inverse(grad)
            ok &= good
            step = np.einsum("...ij,...j->...i", np.where(good[..., None, None], inv, 0.0), res)
            x = x - step
            sane = np.all(np.isfinite(x), axis=-1) & (np.max(np.abs(x), axis=-1) < 1e3 * self.size())
            ok &= sane
            x = np.where(sane[..., None], x, start)
        bar, _, sin_part = self._bars(x, knee)
        res = np.linalg.norm(bar, axis=-1) - b
        tol = FK_RTOL * self.size()
        ok &= np.all(np.abs(res) <= tol, axis=-1) & np.all(sin_part >= 0.0, axis=-1)
        return np.where(ok[..., None], x, np.nan), ok

    @staticmethod
    def _meet(centre: FloatArray, radius: float) -> tuple[FloatArray, BoolArray]:
        """The front point (+z side) at ``radius`` from three centres (..., 3, 3), and whether it exists."""
        o, n, r2 = _circumcentre(centre[..., 0, :], centre[..., 1, :], centre[..., 2, :])
        h2 = radius * radius - r2
        good = np.isfinite(h2) & (h2 >= 0)
        h = np.sqrt(np.where(good, h2, 0.0))
        x = o + h[..., None] * n
        return np.where(good[..., None], x, np.nan), good

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J = A^-1 B`` (..., 3, 3), ``xdot = J qdot``: rows of ``A`` the bars, ``B`` their arm rates."""
        q = as_points("q", q, 3)
        x = self.forward(q)[0] if x is None else as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        a_mat, b_diag = self._velocity_matrices(q, x)
        inv, _ = batched_inverse(a_mat)
        legs, direct = self._classes(a_mat, *self._ratios(a_mat, b_diag, x))
        return singular_limit(inv * b_diag[..., None, :], legs & ~direct[..., None], direct)

    def _velocity_matrices(self, q: ArrayLike, x: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        q = as_points("q", q, 3)
        x = self.forward(q)[0] if x is None else as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        knee, dknee = self._knees(q)
        bar, _, _ = self._bars(x, knee)
        return bar, np.sum(bar * dknee, -1)

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = J^-T = A_bar^T B^-1`` (..., 3, 3): platform force per unit arm torque, N/(N m)."""
        return super().force_map(q, x)

    # -- singularities ----------------------------------------------------------------------
    def singular_tolerances(self, x: ArrayLike) -> FloatArray:
        """Per-leg bound on ``|B_ii| / (|n_i| a) = sin theta3 |sin(bend)|`` at an exactly singular pose, (..., 3).

        ``B_ii = n_i . dk_i/dq_i = a b sin theta3 sin(theta2 - q)`` (``|n_i| = b``): it vanishes
        with the knee stretched or folded (the arm in its forearm's plane, bend 0 or pi) or the
        bars along the motor axis (theta3 0 or pi). At a pose exactly on such a locus the computed
        ratio is rounding only:

        - Knee. ``k = (rho^2 + a^2 - L^2) / (2 a rho)`` (``inverse``) is a handful of roundings of
          terms whose size is ``kappa = (rho^2 + a^2 + L^2) / (2 a rho)``: off by ``dk <= 8 eps kappa``.
          Near ``k = +-1`` the arccos turns that into an arm angle off by ``sqrt(2 dk) =
          sqrt(16 eps kappa)``, and the knee's bend moves ``rho / L`` times as much (law of sines in
          the leg's triangle), at most 1 as a sine.
        - Bars. ``cos theta3 = (P_v + f) / b`` is off by ``<= 4 eps S / b`` (``S`` = ``size()``), so
          theta3 comes back within ``sqrt(8 eps S / b)`` of 0 or pi.

        Each bound is taken with eps four times over: ``tol = min(1, sqrt(64 eps kappa) rho / L) +
        sqrt(32 eps S / b)``, about 3e-7 for the Falcon. A pose the ratio puts below it is within
        rounding of the singular locus. Both terms are square roots of eps because the loci are
        folds of the inverse kinematics (two IK branches meet there).

        Parameters
        ----------
        x : array_like, shape (..., 3)
            Platform points, m.

        Returns
        -------
        ndarray, shape (..., 3)
            Dimensionless; ``nan`` where ``x`` is not finite.

        Examples
        --------
        >>> tol = Delta().singular_tolerances([0.0, 0.0, 0.11])
        >>> bool(np.all((tol > 1e-7) & (tol < 1e-6)))
        True
        """
        p = self.params
        x = as_points("x", x, 3)
        with np.errstate(invalid="ignore", divide="ignore"):
            _, _, _, rho, reach, _ = self._reach_terms(x)
            a = p.upper_arm
            kappa = (rho * rho + a * a + reach * reach) / (2 * a * rho)
            knee = np.minimum(1.0, np.sqrt(64 * _EPS * kappa) * rho / reach)
        return knee + np.sqrt(32 * _EPS * self.size() / p.parallelogram)

    def _leg_ratios(self, q: ArrayLike, x: ArrayLike | None) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Bars ``A`` (..., 3, 3), ``|B_ii| / (|n_i| a)`` (..., 3) and ``singular_tolerances`` (..., 3)."""
        q = as_points("q", q, 3)
        x = self.forward(q)[0] if x is None else as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        a_mat, b_diag = self._velocity_matrices(q, x)
        return (a_mat, *self._ratios(a_mat, b_diag, x))

    def _ratios(self, a_mat: FloatArray, b_diag: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``|B_ii| / (|n_i| a)`` (..., 3) and ``singular_tolerances`` (..., 3) of the bars and arm rates."""
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.abs(b_diag) / (np.linalg.norm(a_mat, axis=-1) * self.params.upper_arm)
        return ratio, self.singular_tolerances(x)

    @staticmethod
    def _classes(a_mat: FloatArray, ratio: FloatArray, tol: FloatArray) -> tuple[BoolArray, BoolArray]:
        """Singular arms (..., 3) and direct singularity (...) (``singular_legs``, ``singularity``)."""
        norms = np.linalg.norm(a_mat, axis=-1)
        finite = np.all(np.isfinite(a_mat), axis=(-2, -1))
        safe = np.where(finite[..., None, None], a_mat, np.eye(3))
        det = np.abs(np.linalg.det(safe))
        direct = finite & (det <= np.sqrt(64 * _EPS) * np.prod(norms, axis=-1))
        with np.errstate(invalid="ignore"):
            legs = finite[..., None] & (ratio <= tol)
        return legs, direct

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Arms at an inverse singularity, bool (..., 3): the arm in its forearm's plane or the bars along its axis.

        ``B_ii = n_i . dk_i/dq_i`` vanishes (the bar is perpendicular to the knee's velocity):
        ``|B_ii| / (|n_i| a)`` at or below ``singular_tolerances(x)``, the bound rounding leaves at
        an exactly singular pose.
        """
        _, ratio, tol = self._leg_ratios(q, x)
        with np.errstate(invalid="ignore"):
            return ratio <= tol

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> np.ndarray:
        """0 none, 1 inverse (an arm's ``B_ii = 0``, ``singular_legs``), 2 direct (the bars coplanar), int8 (...).

        Direct: ``|det A| <= sqrt(64 eps) prod |n_i|``. The rows ``n_i`` are smooth in ``x``, but a
        pose from ``forward`` sits on the fold of the sphere intersection there (its two assemblies
        meet), so ``x`` and with it ``det A / prod |n_i|`` (the sine of the bars' angle from
        coplanar) is off by up to ``sqrt(16 eps)`` at an exactly singular pose; eps is taken four
        times over. A pose both inverse and direct is classed direct (J is unbounded there).
        """
        legs, direct = self._classes(*self._leg_ratios(q, x))
        inverse = np.any(legs, axis=-1)
        return np.where(direct, 2, np.where(inverse, 1, 0)).astype(np.int8)

    def singular_loci(self, samples: int = 40) -> dict[str, FloatArray]:
        """Platform points (k, 3) next to each singular locus, for ``metrics.suprema``; m.

        ``"inverse"``: one arm's knee stretched or folded (bend ``EDGE`` or ``pi - EDGE``) or its
        bars along the motor axis (theta3 ``EDGE`` or ``pi - EDGE``), placed leg by leg from the
        arm angle, the bend and the bar angle over their limit ranges (``samples`` arm angles;
        ``samples // 2`` of the other). ``"all_inverse"``: all three arms' knees stretched or
        folded at once (``J -> 0``), Newton on ``k_i = +-(1 - EDGE^2 / 2)`` from a lattice of starts
        for each of the eight combinations. ``"direct"``: points on the surface where the bars
        are coplanar, bisected to rounding on the edges of a ``samples^3`` lattice over the
        feasible set's bounding box whose two ends are feasible with ``det A`` of opposite signs
        (a locus thinner than a lattice cell can be missed: the claim is then "not found", not
        "absent"). The caller keeps the points that are feasible and inside its domain.
        Computed once per parameter set.

        Examples
        --------
        >>> loci = Delta().singular_loci(samples=8)
        >>> sorted(loci), loci["inverse"].shape[1]
        (['all_inverse', 'direct', 'inverse'], 3)
        """
        return delta_loci.singular_loci(self, samples)

    def leg_angles(self, q: ArrayLike, x: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """Knee bend ``theta2 - q`` and bar angle ``theta3`` of each leg, each (..., 3), rad.

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q``, m.

        Returns
        -------
        knee : ndarray, shape (..., 3)
            ``theta2 - q`` wrapped into ``[-pi, pi)``: 0 with the forearm in the arm's line.
        theta3 : ndarray, shape (..., 3)
            Angle of the bars from the motor axis ``v``, in ``[0, pi]``.
        """
        q = as_points("q", q, 3)
        x = self.forward(q)[0] if x is None else as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        knee, _ = self._knees(q)
        u, _ = self.leg_frames()
        bar, along, sin_part = self._bars(x, knee)
        qv = x[..., None, :] - knee
        theta2 = np.arctan2(qv[..., 2], np.sum(qv * u, -1))
        bend = theta2 - q
        bend = bend - 2 * np.pi * np.floor((bend + np.pi) / (2 * np.pi))
        theta3 = np.arctan2(sin_part, along)
        return bend, theta3

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Arm angles, knee bends and bar angles within their limits, bool (...)."""
        p = self.params
        q = as_points("q", q, 3)
        if x is None:
            x, assembled = self.forward(q)
        else:
            x = as_points("x", x, 3)
            assembled = np.all(np.isfinite(x), axis=-1)
        q, x = np.broadcast_arrays(q, x)
        finite = np.all(np.isfinite(q), axis=-1) & assembled & np.all(np.isfinite(x), axis=-1)
        qs, _ = finite_rows(np.where(finite[..., None], q, 0.3), [0.3, 0.3, 0.3])
        xs, _ = finite_rows(np.where(finite[..., None], x, 0.0), [0.0, 0.0, 0.15])
        bend, theta3 = self.leg_angles(qs, xs)
        ok = ((qs >= p.arm_lower) & (qs <= p.arm_upper) & (bend >= p.knee_min) & (bend <= p.knee_max)
              & (np.abs(theta3 - np.pi / 2) <= p.bar_limit))
        return finite & np.all(ok, axis=-1)

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline through the three legs for drawing, (..., 19, 3), m.

        Per leg: motor axis point, knee, the parallelogram's two ends, the platform hinge;
        the legs are joined through the base centre and the platform point. ``nan`` where ``q``
        does not assemble.
        """
        p = self.params
        q = as_points("q", q, 3)
        x, _ = self.forward(q)
        u, v = self.leg_frames()
        qs, _ = finite_rows(q, [0.3, 0.3, 0.3])
        knee_eff, _ = self._knees(qs)
        shift = p.platform_offset_u * u + p.platform_offset_v * v          # (3, 3)
        knee = knee_eff + shift
        base = p.base_radius * u + p.base_offset_v * v
        bar, _, _ = self._bars(x, knee_eff)
        qv = x[..., None, :] - knee_eff
        perp = qv - np.sum(qv * v, -1)[..., None] * v
        rho = np.linalg.norm(perp, axis=-1)
        radial = perp / np.where(rho > 0, rho, 1.0)[..., None]
        top = knee + p.knee_offset * radial
        end = top + bar
        hinge = end + p.platform_joint_offset * radial
        origin = np.zeros_like(x)
        base = np.broadcast_to(base, knee.shape)

        def leg(i, reverse=False):
            pts = [base[..., i, :], knee[..., i, :], top[..., i, :], end[..., i, :], hinge[..., i, :]]
            return pts[::-1] if reverse else pts

        seq = [origin, *leg(0), x, *leg(1, True), origin, *leg(2), x]
        return np.stack(seq, -2)
