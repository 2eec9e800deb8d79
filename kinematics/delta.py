"""Delta-type parallel positioner: three rotary arms, parallelogram forearms, a translating platform.

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

from .base import BoolArray, FloatArray, MechanismBase, ParamInfo, as_points, positive_finite, positive_vector
from .rotations import angle_in, batched_inverse, finite_rows

ARMS = ("q1", "q2", "q3")
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

    def __post_init__(self) -> None:
        set_ = object.__setattr__
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
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ARMS))


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
    )

    def __init__(self, params: DeltaParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else DeltaParams(**kwargs))

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

    def torque_limits(self) -> FloatArray:
        """Arm-side torque limits ``motor_torque_i * gear_ratio_i`` (3,), N m.

        Returns
        -------
        ndarray, shape (3,)
        """
        return np.asarray(self.params.motor_torques, float) * np.asarray(self.params.gear_ratios, float)

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
        """Arm angles ``q`` (..., 3) reaching platform points ``x`` (..., 3), closed form per arm.

        Parameters
        ----------
        x : array_like, shape (..., 3)
            Platform points, m.

        Returns
        -------
        q : ndarray, shape (..., 3)
            Arm angles in ``[-pi, pi)``, rad; ``nan`` where unreachable.
        reachable : ndarray of bool, shape (...)
            Every arm's bar angle and circle intersection exist (limits are ``feasible``'s).
        """
        p = self.params
        x = as_points("x", x, 3)
        x, finite = finite_rows(x, [0.0, 0.0, 0.15])
        u, v = self.leg_frames()
        big_d = p.knee_offset + p.platform_joint_offset
        pu = x @ u.T - p.base_radius + p.platform_offset_u        # (..., 3): P_u + c
        pv = x @ v.T - p.base_offset_v + p.platform_offset_v      # P_v + f = b cos theta3
        pw = x[..., 2:3] + np.zeros(3)
        cos3 = pv / p.parallelogram
        ok3 = np.abs(cos3) <= 1.0
        sin3 = np.sqrt(np.clip(1.0 - cos3 * cos3, 0.0, None))
        reach = big_d + p.parallelogram * sin3                    # L
        rho = np.hypot(pu, pw)
        safe = np.where(rho > 0, rho, 1.0)
        k = (rho * rho + p.upper_arm ** 2 - reach * reach) / (2 * p.upper_arm * safe)
        ok1 = (rho > 0) & (np.abs(k) <= 1.0)
        q = np.arctan2(pw, pu) - np.arccos(np.clip(k, -1.0, 1.0))
        q = q - 2 * np.pi * np.floor((q + np.pi) / (2 * np.pi))
        ok = finite & np.all(ok3 & ok1, axis=-1)
        return np.where(ok[..., None], q, np.nan), ok

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Platform point ``x`` (..., 3) of arm angles ``q`` (..., 3): sphere intersection, then Newton.

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.

        Returns
        -------
        x : ndarray, shape (..., 3)
            m; ``nan`` where it does not assemble or the solver did not converge.
        ok : ndarray of bool, shape (...)
            Assembled and converged, on libnifalcon's branch (``sin theta3 >= 0``), in front
            of the knees.
        """
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
        """``J = A^-1 B`` (..., 3, 3), ``xdot = J qdot``: rows of ``A`` the bars, ``B`` their arm rates.

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q`` (``forward(q)`` when not given), m.

        Returns
        -------
        ndarray, shape (..., 3, 3)
            m/rad; ``inf`` at a direct singularity, ``nan`` where ``q`` or ``x`` is not finite.
        """
        a_mat, b_diag = self._velocity_matrices(q, x)
        inv, _ = batched_inverse(a_mat)
        return inv * b_diag[..., None, :]

    def _velocity_matrices(self, q: ArrayLike, x: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        q = as_points("q", q, 3)
        x = self.forward(q)[0] if x is None else as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        knee, dknee = self._knees(q)
        bar, _, _ = self._bars(x, knee)
        return bar, np.sum(bar * dknee, -1)

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = J^-T = A_bar^T B^-1`` (..., 3, 3): platform force per unit arm torque, N/(N m).

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q``, m.

        Returns
        -------
        ndarray, shape (..., 3, 3)
            ``nan`` where ``J`` is singular or not finite.
        """
        return super().force_map(q, x)

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Arms at an inverse singularity (bar in line with the arm's motion plane normal), bool (..., 3).

        ``|B_ii| <= 1e-9 |n_i| a``: the bar is perpendicular to the knee's velocity.

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q``, m.

        Returns
        -------
        ndarray of bool, shape (..., 3)
        """
        a_mat, b_diag = self._velocity_matrices(q, x)
        scale = np.linalg.norm(a_mat, axis=-1) * self.params.upper_arm
        return np.abs(b_diag) <= 1e-9 * scale

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> np.ndarray:
        """0 none, 1 inverse (an arm's ``B_ii = 0``), 2 direct (the bars' matrix near singular), int8 (...).

        Direct: ``|det A| <= 1e-9 prod |n_i|`` (the bars nearly coplanar).

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q``, m.

        Returns
        -------
        ndarray of int8, shape (...)
        """
        a_mat, b_diag = self._velocity_matrices(q, x)
        norms = np.linalg.norm(a_mat, axis=-1)
        finite = np.all(np.isfinite(a_mat), axis=(-2, -1))
        safe = np.where(finite[..., None, None], a_mat, np.eye(3))
        det = np.abs(np.linalg.det(safe))
        direct = finite & (det <= 1e-9 * np.prod(norms, axis=-1))
        inverse = finite & np.any(np.abs(b_diag) <= 1e-9 * norms * self.params.upper_arm, axis=-1)
        return np.where(direct, 2, np.where(inverse, 1, 0)).astype(np.int8)

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
        """Arm angles, knee bends and bar angles within their limits, bool (...).

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.
        x : array_like, shape (..., 3), optional
            The platform point of ``q``, m.

        Returns
        -------
        ndarray of bool, shape (...)
            ``False`` where ``q`` or ``x`` is not finite.
        """
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

        Parameters
        ----------
        q : array_like, shape (..., 3)
            Arm angles, rad.

        Returns
        -------
        ndarray, shape (..., 19, 3)
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
