"""Stewart platform: six prismatic legs between a base and a platform (paper 001, sec. V).

Paper 001 compares a Stewart platform with the Twin-Pantograph; its Fig. 10 (the geometry
behind Table IV's ``l1, l4..l7, eta1, eta2``) is not in our text. We use the common
three-fold-symmetric 6-6 layout, with every length and angle a parameter:

* Base joints (universal) on a circle of radius ``base_radius`` in the plane ``z = 0``, in
  three pairs centred at azimuths 90, 210, 330 deg, the two joints of a pair at
  +-``base_half_angle`` from its centre.
* Platform joints (spherical) on a circle of radius ``platform_radius`` in the platform plane,
  in three pairs centred at 30, 150, 270 deg (60 deg from the base pairs), +-
  ``platform_half_angle``. Leg ``i`` (0-based, ``k = i // 2``, ``s = -1`` for even ``i``,
  ``+1`` for odd) joins the base joint at ``90 + 120 k + s eta_b`` to the platform joint at
  ``90 + 120 k + s (60 - eta_p)`` deg: the usual zig-zag. Legs 1-2, 3-6 and 4-5 (1-based)
  are mirror images in the ``yz`` plane, the pairs paper 001 gives one scale factor each
  (its eq. 18).
* The task point (the paper's platform origin ``o_p``, where the pen is held) is
  ``tool_offset`` above the platform's joint plane along its normal. With legs of 9-18 cm
  (the paper's comparison) a tool offset of ~10 cm puts it near the paper's 25 cm workspace
  distance; we read Table IV's ``l1`` (optimum 10 cm) as this offset, and ``l4``/``l6`` (6 and
  3 cm, "platforms half as large as the bases") as the two radii. ``l5``, ``l7``, ``eta1``,
  ``eta2`` are not mapped: the paper's eta range (110-175 deg) is not a pair half-angle of
  this layout (which must be below 60 deg).
* Joint bend: the angle of a leg from the plate normal at each end (``e_z`` at the base,
  ``R e_z`` at the platform), limited by ``base_joint_limit`` / ``platform_joint_limit``.
  Legs may pass through each other (no collision model).

Coordinates, Jacobian, statics
------------------------------
``x = (x, y, z, rx, ry, rz)``: task point (m) and rotation vector of the platform (rad, base
frame). Legs ``q`` (m). Leg i's vector ``L_i = o + R p_i - b_i`` (``p_i`` the platform joint in
the platform frame, whose origin is the task point), ``q_i = |L_i|``, ``u_i = L_i / q_i``.
The IK Jacobian ``K`` has rows ``[u_i^T, ((R p_i) x u_i)^T]``: ``qdot = K xi`` with the
twist ``xi = [v; omega]`` (task point velocity and angular velocity, base frame). Our
``jacobian`` is ``J = K^-1`` (``xi = J qdot``, DESIGN.md's convention) and statics are
``tau = J^T w`` for the wrench ``w = [f; m]`` (force, and moment about the task point, base
frame) with leg forces ``tau`` (N, positive pushing the platform away): ``w = K^T tau``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, memoised
from .bodies import Body, body_arrays, columns, cross3, dot3, link_part, rod, stack_bodies
from .mass_params import G_CM2, MASS_MODELS, MOMENTS, check_mass_params, link_frames
from .pose_memo import PoseMemo, per_block
from .rotations import (
    angle_in,
    batched_inverse,
    finite_rows,
    left_jacobian,
    pose_rates_to_twist,
    rotation_matrix,
    rotation_vector,
)
from .validation import as_points, optional_positive_vector, positive_finite, positive_vector
from .vector_rows import angle_between as row_angle
from .vector_rows import dot as row_dot

LEGS = ("L1", "L2", "L3", "L4", "L5", "L6")
#: ``link_masses``: the mass of each leg's cylinder (on the base's universal joint) and of each
#: leg's piston (on the platform's spherical joint), the same for the six legs.
LINKS = ("cylinder", "piston")
_DEG = np.pi / 180.0
_EPS = np.finfo(np.float64).eps
#: Default FK convergence tolerance, relative to ``StewartPlatform.residual_scale`` (``S``).
#: Derivation (``u = eps / 2``, ``gamma_n ~ n u``; every vector below is bounded by ``S``):
#: evaluating ``r_i = |o + R p_i - b_i| - q_i`` costs at most ``gamma_3 sqrt(3) |p_i|``
#: (``R p_i``, three-term dot products with ``|R_jk| <= 1``) ``+ u (|o| + |p_i|) + u |L_i|`` (the
#: two additions) ``+ 2.5 u |L_i|`` (the 2-norm of a 3-vector) ``+ u |r_i|``, below ``8 u S =
#: 4 eps S``; the iterate itself is rounded when stored (``o + dv``: ``sqrt(3) u |o|``;
#: ``exp([w]x) R``: ``gamma_3 sqrt(3) |p_i|`` on ``R p_i``), below ``6 u S = 3 eps S``. So at
#: the exact solution's nearest representable neighbour the computed residual is below
#: ``7 eps S``; ``16 eps`` (about twice that) is attainable on every CPU and SIMD path, and
#: still 1e-15 m for the default geometry (S ~ 0.3 m). An absolute tolerance is not: at 1e9 m
#: legs a single rounding of a leg length is 1.2e-7 m.
FK_RTOL = 16 * _EPS


@dataclass(frozen=True, slots=True)
class StewartParams:
    """Geometry (m, rad), leg range (m), joint limits (rad) and leg forces (N) of a Stewart platform.

    Defaults: radii 6 and 3 cm and tool offset 10 cm (our reading of paper 001 Table IV's
    optimum), pair half-angles 15 deg, legs 9-18 cm (the paper's comparison), joint bends up to
    85 deg, 10 N per leg (illustrative).
    """

    base_radius: float = 0.06
    platform_radius: float = 0.03
    base_half_angle: float = 15 * _DEG
    platform_half_angle: float = 15 * _DEG
    tool_offset: float = 0.10
    min_leg: float = 0.09
    max_leg: float = 0.18
    base_joint_limit: float = 85 * _DEG
    platform_joint_limit: float = 85 * _DEG
    motor_forces: tuple[float, ...] = (10.0,) * 6
    gear_ratios: tuple[float, ...] = (1.0,) * 6
    #: Each motor's largest (no-load) speed, motor side, m/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    #: Mass model (``kinematics.mass_params``): each leg's cylinder and piston a uniform rod of
    #: ``min_leg / 2`` from its joint along the leg; the platform (mass, principal moments about its
    #: centre in the joint plane); each actuator's moving inertia felt at the leg as a mass, kg
    #: (``rotor_inertias``; ``gear_ratios`` multiply it squared). The defaults are the shipped
    #: preset's estimates (``resources/presets/stewart_platform.toml``, in g cm^2 there).
    link_masses: tuple[float, float] = (0.03, 0.015)
    platform_mass: float = 0.05
    platform_inertia: tuple[float, float, float] = (200 * 1e-7, 200 * 1e-7, 400 * 1e-7)
    rotor_inertias: tuple[float, ...] = (0.01,) * 6
    mass_model: str = "estimated"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, LEGS, scalars=("platform_mass",), moments=("platform_inertia",))
        for name in ("base_radius", "platform_radius", "min_leg", "max_leg"):
            set_(self, name, positive_finite(name, getattr(self, name), "m"))
        try:
            offset = float(self.tool_offset)
        except (TypeError, ValueError):
            offset = np.nan
        if not np.isfinite(offset):
            raise ValueError(f"tool_offset must be a finite number in m, got {self.tool_offset!r}")
        set_(self, "tool_offset", offset)
        for name in ("base_half_angle", "platform_half_angle"):
            set_(self, name, angle_in(name, getattr(self, name), 0.0, np.pi / 3))
        for name in ("base_joint_limit", "platform_joint_limit"):
            set_(self, name, angle_in(name, getattr(self, name), 0.0, np.pi, open_lower=True))
        if not self.min_leg < self.max_leg:
            raise ValueError(f"min_leg must be below max_leg, got {self.min_leg} >= {self.max_leg}")
        set_(self, "motor_forces", positive_vector("motor_forces", self.motor_forces, LEGS, "N"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, LEGS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, LEGS, "m/s"))


#: The last ``_legs`` each thread computed, keyed on the model and the exact poses
#: (``kinematics.pose_memo``).
_LAST_LEGS = PoseMemo()


class StewartPlatform(MechanismBase):
    """Six-leg Stewart platform, ``q`` = leg lengths (m), ``x`` = 6-DOF pose. See the module doc."""

    n_joints = 6
    task_dim = 6
    joint_names = LEGS
    task_names = ("x", "y", "z", "rx", "ry", "rz")
    task_units = ("m", "m", "m", "rad", "rad", "rad")
    #: Actuated joints are prismatic legs (lengths), not angles.
    joint_units = ("m",) * 6

    @property
    def characteristic_length(self) -> float:
        """Moment arm (m) for comparing moments with forces: the platform radius.

        A leg force ``F`` produces a moment about the task point of order ``F`` times the
        platform joint circle's radius, so moments over this length are forces of the same
        order (``metrics.wrenches``: the condition number's task scaling).
        """
        return self.params.platform_radius
    PARAM_INFO = (
        ParamInfo("base_radius", "mm", 1e-3, "Radius of the base joint circle"),
        ParamInfo("platform_radius", "mm", 1e-3, "Radius of the platform joint circle"),
        ParamInfo("base_half_angle", "deg", _DEG, "Half the angle between the two base joints of a pair"),
        ParamInfo("platform_half_angle", "deg", _DEG, "Half the angle between the two platform joints of a pair"),
        ParamInfo("tool_offset", "mm", 1e-3, "Height of the task point above the platform joint plane"),
        ParamInfo("min_leg", "mm", 1e-3, "Shortest leg (fully retracted)"),
        ParamInfo("max_leg", "mm", 1e-3, "Longest leg (fully extended)"),
        ParamInfo("base_joint_limit", "deg", _DEG, "Largest leg angle from the base normal"),
        ParamInfo("platform_joint_limit", "deg", _DEG, "Largest leg angle from the platform normal"),
        ParamInfo("motor_forces", "N", 1.0, "Continuous actuator force", LEGS),
        ParamInfo("gear_ratios", "", 1.0, "Force multiplication of the leg's transmission", LEGS),
        ParamInfo("link_masses", "kg", 1.0, "Body masses of each leg (uniform rods of min_leg / 2: cylinder "
                  "from the base joint, piston from the platform joint)", LINKS),
        ParamInfo("platform_mass", "kg", 1.0, "Platform mass (centre in the joint plane, under the task point)"),
        ParamInfo("platform_inertia", "g cm^2", G_CM2, "Platform principal moments about its centre "
                  "(z: the platform normal)", MOMENTS),
        ParamInfo("rotor_inertias", "g", 1e-3, "Actuator moving inertia felt at the leg as a mass (times the "
                  "ratio squared)", LEGS),
        ParamInfo("mass_model", "", 1.0, "Body masses are estimated, the device's (given), or there is no "
                  "mass model (none)", choices=MASS_MODELS),
    )
    mass_coordinates = "task"

    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """Six cylinders, six pistons (uniform rods along body x) and the platform."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        half = 0.5 * p.min_leg
        return (*(rod(f"cylinder_{i + 1}", p.link_masses[0], half) for i in range(6)),
                *(rod(f"piston_{i + 1}", p.link_masses[1], half) for i in range(6)),
                Body("platform", p.platform_mass, (0.0, 0.0, -p.tool_offset), (*p.platform_inertia, 0.0, 0.0, 0.0)))

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame, (..., 13, 3, 3) and (..., 13, 3), m.

        Cylinder i: origin at the base joint ``b_i``, x along the leg; piston i: origin at the
        platform joint, x towards the base joint; the twist about the leg is immaterial to a rod
        of no radius (the frames take their y axis across the leg and the base's tangent at
        ``b_i``, never along a leg within the 90 deg joint range). Platform: ``R(x)`` at the task point.
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        x = as_points("x", x, 6)
        rot, arm, legs = self._legs(x)
        base = np.broadcast_to(self.base_joints(), legs.shape)
        top = base + legs
        tangent = np.cross([0.0, 0.0, 1.0], self.base_joints())
        tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
        cyl = link_frames(base, top, tangent)
        pis = link_frames(top, base, tangent)
        rotations = np.concatenate([cyl, pis, rot[..., None, :, :]], axis=-3)
        origins = np.concatenate([base, top, x[..., None, :3]], axis=-2)
        return rotations, origins

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (13, 3, 6, N), ``R_b`` (13, 3, 3, N) and ``G = dq/dx`` (6, 6, N).

        Component-first (``kinematics.bodies``), in the rates of the pose coordinates ``x`` (the
        position and the rotation vector ``r``, as ``body_poses`` is placed): the platform turns at
        ``omega = J_l(r) rdot`` (``rotations.left_jacobian``), so leg i's platform joint moves at
        ``pdot + omega x R p_i`` and its length at ``u_i . (that)`` (``G``'s row i).
        """
        x = as_points("x", x, 6).reshape(-1, 6)
        rot, arm, legs = self._legs(x)
        left = columns(per_block(left_jacobian, x[:, 3:6]))                                # (3, 3, N)
        rot, arm, legs = columns(rot), columns(arm), columns(legs)                         # (3, 3, N), (6, 3, N)
        n = rot.shape[-1]
        base = np.broadcast_to(self.base_joints()[..., None], (6, 3, n))
        top = base + legs
        tangent = np.cross([0.0, 0.0, 1.0], self.base_joints())
        tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
        dpos = np.zeros((3, 6, n))
        dpos[0, 0] = dpos[1, 1] = dpos[2, 2] = 1.0
        still = np.zeros((3, 6, n))
        omega = np.concatenate([np.zeros((3, 3, n)), left], axis=1)          # the platform's, (3, 6, N)
        cylinders, pistons, g = [], [], []
        for i in range(6):
            dleg = dpos.copy()
            dleg[:, 3:] = cross3(left, arm[i][:, None])                      # (J_l e_j) x R p_i
            ti = tangent[i][:, None]
            cylinder = link_part(base[i], top[i], ti, still, dleg)
            cylinders.append(cylinder)
            # The piston's frame is the cylinder's from the other end: e_x and e_y reversed, e_z and
            # the angular velocity the same. Exactly so in floating point (every term of
            # link_frame_rates changes only sign with b - a and b' - a'), without a second pass.
            ex, ey, ez = (cylinder[0][:, k] for k in range(3))
            pistons.append((np.stack([-ex, -ey, ez], axis=1), cylinder[1], dleg))
            g.append(dot3(legs[i][:, None], dleg) / np.sqrt(dot3(legs[i], legs[i])))
        platform = (rot, omega, dpos)
        jv, jw, rots = stack_bodies([*cylinders, *pistons, platform], body_arrays(self.bodies())[1])
        return jv, jw, rots, np.stack(g)

    def __init__(self, params: StewartParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else StewartParams(**kwargs))

    # -- geometry ---------------------------------------------------------------------------
    def _angles(self) -> tuple[FloatArray, FloatArray]:
        k = np.repeat(np.arange(3), 2)
        s = np.tile([-1.0, 1.0], 3)
        centre = 90 * _DEG + 120 * _DEG * k
        return centre + s * self.params.base_half_angle, centre + s * (60 * _DEG - self.params.platform_half_angle)

    def base_joints(self) -> FloatArray:
        """Base joint centres ``b_i`` in the base frame, (6, 3), m.

        Returns
        -------
        ndarray, shape (6, 3)
            Row i is ``b_i``, m.
        """
        phi, _ = self._angles()
        r = self.params.base_radius
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.zeros(6)], -1)

    def platform_joints(self) -> FloatArray:
        """Platform joint centres ``p_i`` in the platform frame (origin at the task point), (6, 3), m.

        Returns
        -------
        ndarray, shape (6, 3)
            Row i is ``p_i``, m.
        """
        _, phi = self._angles()
        r = self.params.platform_radius
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.full(6, -self.params.tool_offset)], -1)

    def torque_limits(self) -> FloatArray:
        """Leg force limits ``motor_force_i * gear_ratio_i`` (6,), N."""
        return np.asarray(self.params.motor_forces, float) * np.asarray(self.params.gear_ratios, float)

    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """Shortest and longest leg (m), each (6,).

        Returns
        -------
        lower, upper : ndarray, shape (6,)
            m.
        """
        return np.full(6, self.params.min_leg), np.full(6, self.params.max_leg)

    def home_pose(self) -> FloatArray:
        """Zero orientation, centred, every leg at mid-stroke, (6,).

        Returns
        -------
        ndarray, shape (6,)
            ``(x, y, z, rx, ry, rz)``, m and rad.

        Examples
        --------
        >>> StewartPlatform().home_pose().shape
        (6,)
        """
        b, p = self.base_joints(), self.platform_joints()
        horizontal = np.hypot(*(p[0, :2] - b[0, :2]))
        mid = 0.5 * (self.params.min_leg + self.params.max_leg)
        height = np.sqrt(max(mid * mid - horizontal * horizontal, 0.0))
        return np.array([0.0, 0.0, height + self.params.tool_offset, 0.0, 0.0, 0.0])

    def _legs(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Rotation (..., 3, 3), rotated platform joints ``R p_i`` (..., 6, 3), leg vectors (..., 6, 3).

        Non-finite poses give ``nan`` throughout (computed on a placeholder, without warnings).
        The last batch's are kept (``_LAST_LEGS``): a map asks for the limits, ``jacobian``,
        ``force_map`` and the mass matrix at the same poses. Read-only.
        """
        x = np.asarray(x, dtype=float)
        legs = _LAST_LEGS.get(self, x)
        return legs if legs is not None else _LAST_LEGS.put(self, x, self._build_legs(x))

    def _build_legs(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        x, finite = finite_rows(x, self.home_pose())
        rot, arm = per_block(self._turned, x[..., 3:6])          # once per orientation of a repeating block
        legs = x[..., None, :3] + arm - self.base_joints()
        if not finite.all():
            bad = ~finite
            rot, arm, legs = rot.copy(), arm.copy(), legs.copy()
            rot[bad], arm[bad], legs[bad] = np.nan, np.nan, np.nan
        return rot, arm, legs

    def _turned(self, rotvec: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Rotations (..., 3, 3) of rotation vectors (..., 3) and the platform joints turned, ``R p_i`` (..., 6, 3)."""
        rot = rotation_matrix(rotvec)
        return rot, np.einsum("...ij,kj->...ki", rot, self.platform_joints())

    # -- kinematics -------------------------------------------------------------------------
    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Leg lengths ``q`` (..., 6) for poses ``x`` (..., 6); ``ok`` where ``x`` is finite.

        Every pose has leg lengths (closed form); the range is checked by ``feasible``.

        Examples
        --------
        >>> mech = StewartPlatform()
        >>> q, ok = mech.inverse(mech.home_pose())
        >>> q.shape, bool(ok)
        ((6,), True)
        """
        x = as_points("x", x, 6)
        _, _, legs = self._legs(x)
        q = np.sqrt(row_dot(legs, legs))                     # np.linalg.norm(legs, axis=-1), bit for bit
        return q, np.all(np.isfinite(q), axis=-1)

    def coordinate_rates_to_twist(self, x: ArrayLike) -> FloatArray:
        """``T = blockdiag(I, J_l(r))`` (..., 6, 6), ``xi = T xdot`` (``rotations.pose_rates_to_twist``)."""
        return pose_rates_to_twist(as_points("x", x, 6))

    def inverse_jacobian(self, q: ArrayLike | None = None, x: ArrayLike | None = None) -> FloatArray:
        """``K`` (..., 6, 6), rows ``[u_i^T, ((R p_i) x u_i)^T]``: ``qdot = K [v; omega]``.

        Needs the pose ``x``; computed from ``q`` by ``forward`` when not given.

        Parameters
        ----------
        q : array_like, shape (..., 6), optional
            Leg lengths, m (used only when ``x`` is not given).
        x : array_like, shape (..., 6), optional
            Poses, m and rad.

        Returns
        -------
        ndarray, shape (..., 6, 6)
            Dimensionless on the ``v`` columns, m on the ``omega`` columns.

        Raises
        ------
        ValueError
            If neither ``q`` nor ``x`` is given.
        """
        x = self._pose(q, x)
        _, arm, legs = self._legs(x)
        length = np.sqrt(row_dot(legs, legs))[..., None]     # np.linalg.norm, bit for bit
        with np.errstate(divide="ignore", invalid="ignore"):
            u = legs / length
        return np.concatenate([u, np.cross(arm, u)], -1)

    def force_map(self, q: ArrayLike | None = None, x: ArrayLike | None = None) -> FloatArray:
        """``A = K^T`` (..., 6, 6): the wrench ``w = [f; m] = A tau`` of leg forces ``tau``."""
        return np.swapaxes(self.inverse_jacobian(q, x), -1, -2)

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J = K^-1`` (..., 6, 6): ``[v; omega] = J qdot``; ``tau = J^T w``. ``inf`` where singular.

        Examples
        --------
        >>> mech = StewartPlatform()
        >>> x = mech.home_pose()
        >>> q, _ = mech.inverse(x)
        >>> mech.jacobian(q, x).shape
        (6, 6)
        """
        inv, _ = batched_inverse(self.inverse_jacobian(q, x))
        return inv

    def _pose(self, q: ArrayLike | None, x: ArrayLike | None) -> FloatArray:
        if x is None:
            if q is None:
                raise ValueError("inverse_jacobian needs the pose x or the legs q, got neither")
            x, _ = self.forward(q)
        return as_points("x", x, 6)

    def forward(self, q: ArrayLike, guess: ArrayLike | None = None, *, rtol: float = FK_RTOL,
                max_iter: int = 50) -> tuple[FloatArray, BoolArray]:
        """Pose ``x`` (..., 6) with leg lengths ``q`` (..., 6), by Newton's method, and ``converged``.

        Starts from ``guess`` (..., 6) (default ``home_pose()``, so the assembly with the
        platform above the base and the same handedness); each step solves ``K dxi = -(q(x) -
        q)`` and updates ``o += dv``, ``R = exp([domega]x) R``. Quadratic convergence: a pose
        inside the workspace takes ~5 steps from home.

        Converged where every leg residual ``|q_i(x) - q_i| <= rtol * scale``, with ``scale``
        (m) the device's size at that pose, ``max_i q_i + max_i |p_i| + max_i |b_i|`` (longest
        leg plus the platform and base joint radii, tool offset included). The criterion is
        relative because a residual cannot be computed more accurately than that: see
        ``FK_RTOL`` for the derivation of the default ``16 eps``. The rest get ``nan`` and
        ``converged = False``. Near a singularity (legs nearly parallel, e.g. legs much longer
        than the plates) Newton may stall above the tolerance; that pose is then reported as
        not converged, never as a wrong pose.
        """
        q, finite = finite_rows(as_points("q", q, 6), self.joint_limits()[1])
        batch = q.shape[:-1]
        start = self.home_pose() if guess is None else np.asarray(guess, float)
        x = np.array(np.broadcast_to(start, batch + (6,)), dtype=np.float64)
        centre = x[..., :3].copy()
        rot = rotation_matrix(x[..., 3:6])
        done = np.zeros(batch, bool)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            tol = rtol * self.residual_scale(q)
            centre, rot, done = self._newton(q, centre, rot, done, tol, max_iter)
        done &= finite
        x = np.concatenate([centre, rotation_vector(rot)], -1)
        return np.where(done[..., None], x, np.nan), done

    def residual_scale(self, q: ArrayLike) -> FloatArray:
        """Size of the device (m) at leg lengths ``q`` (..., 6): ``max q_i + max |p_i| + max |b_i|``, (...).

        Bounds every vector that enters a leg residual (``|o| <= |L_i| + |p_i| + |b_i|``), so
        the residual's rounding error is a small multiple of ``eps * scale`` (``FK_RTOL``).
        Non-finite legs are ignored (their pose is masked anyway).

        Parameters
        ----------
        q : array_like, shape (..., 6)
            Leg lengths, m.

        Returns
        -------
        ndarray, shape (...)
            m.
        """
        q = np.abs(np.asarray(q, dtype=np.float64))
        legs = np.max(np.where(np.isfinite(q), q, 0.0), axis=-1)
        plates = (np.max(np.linalg.norm(self.platform_joints(), axis=-1))
                  + np.max(np.linalg.norm(self.base_joints(), axis=-1)))
        return legs + plates

    def _newton(self, q, centre, rot, done, tol, max_iter):
        """Newton steps on the leg residuals; non-finite or singular steps are skipped."""
        for _ in range(max_iter):
            arm = np.einsum("...ij,kj->...ki", rot, self.platform_joints())
            legs = centre[..., None, :] + arm - self.base_joints()
            length = np.linalg.norm(legs, axis=-1)
            residual = length - q
            done = np.all(np.abs(residual) <= tol[..., None], axis=-1)
            if done.all():
                break
            u = legs / length[..., None]
            k = np.concatenate([u, np.cross(arm, u)], -1)
            inv, ok = batched_inverse(k)
            step = -np.einsum("...ij,...j->...i", np.where(ok[..., None, None], inv, 0.0), residual)
            step = np.where((done | ~ok)[..., None] | ~np.isfinite(step), 0.0, step)
            centre = centre + step[..., :3]
            rot = rotation_matrix(step[..., 3:]) @ rot
        return centre, rot, done

    # -- limits -----------------------------------------------------------------------------
    def bend_angles(self, x: ArrayLike) -> FloatArray:
        """Leg angle from the base normal and from the platform normal, (..., 6, 2), rad.

        Parameters
        ----------
        x : array_like, shape (..., 6)
            Poses, m and rad.

        Returns
        -------
        ndarray, shape (..., 6, 2)
            Per leg: bend at the base joint, bend at the platform joint, rad.
        """
        x = as_points("x", x, 6)
        rot, _, legs = self._legs(x)
        base = row_angle(legs, np.array([0.0, 0.0, 1.0]))
        top = row_angle(legs, rot[..., None, :, 2])
        return np.stack([base, top], -1)

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Leg lengths in ``[min_leg, max_leg]`` and joint bends within their limits, shape (...)."""
        q = as_points("q", q, 6)
        x = self._pose(q, x)
        p = self.params
        bends = self.bend_angles(x)
        with np.errstate(invalid="ignore"):
            ok = np.all(np.isfinite(q), axis=-1)
            ok &= np.all((q >= p.min_leg) & (q <= p.max_leg), axis=-1)
            ok &= np.all(bends[..., 0] <= p.base_joint_limit, axis=-1)
            ok &= np.all(bends[..., 1] <= p.platform_joint_limit, axis=-1)
        return ok

    # -- drawing ----------------------------------------------------------------------------
    def link_points(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """One polyline (..., 26, 3) through every link, m; some edges are traced twice.

        ``b1..b6, b1, p1, p2, b2, b3, p3, p4, b4, b5, p5, p6, b6, p6, p1, p2, p3, p4, p5, c, o``
        with ``b``/``p`` the base/platform joints, ``c`` the platform centre and ``o`` the task
        point: the base hexagon, the six legs, the platform hexagon, a spoke and the tool stem.
        ``x`` is the pose of ``q`` (computed by ``forward`` when not given).
        """
        x = self._pose(q, x)
        rot, arm, _ = self._legs(x)
        o = x[..., :3]
        top = o[..., None, :] + arm                                    # (..., 6, 3)
        base = np.broadcast_to(self.base_joints(), top.shape)
        b = [base[..., i, :] for i in range(6)]
        t = [top[..., i, :] for i in range(6)]
        centre = o - self.params.tool_offset * rot[..., :, 2]
        seq = b + [b[0], t[0], t[1], b[1], b[2], t[2], t[3], b[3], b[4], t[4], t[5], b[5], t[5],
                   t[0], t[1], t[2], t[3], t[4], centre, o]
        return np.where(np.all(np.isfinite(x), -1)[..., None, None], np.stack(seq, -2), np.nan)

