"""Inverse3 prototype (Łącki, Rossa, Gallacher, paper 000), as reconstructed in DESIGN.md.

A base revolute joint ``theta_0`` about the vertical z axis carries a planar five-bar whose
two motors are coaxial at the plane's centre. DH rows ``Rot_x(alpha) Trans_z(d)
Rot_z(theta) Trans_x(a)`` (paper 000 Table 1) give, with ``u = a3 cos th3`` and
``w = a3 sin th3`` the end-effector in the five-bar plane and ``c = tool_offset -
shoulder_offset`` (22.3 mm),

    P = (u cos th0 - c sin th0,  u sin th0 + c cos th0,  base_height + w).

Five-bar: link angles ``phi`` in the plane from the radial axis towards +z,
``th3 = (phi1 + phi2) / 2``, ``h = (phi1 - phi2) / 2``,
``a3 = l1 cos h + sqrt(l2^2 - l1^2 sin^2 h)``. Motor angle = link angle + 90 deg (zero
points down, positive towards the radial axis); motor p1 drives the upper link (h > 0).
The Jacobian is with respect to ``q = (theta_0, theta_p1, theta_p2)`` in rad, output in m.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .angles import wrap_into
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, memoised
from .bodies import (
    Body,
    body_arrays,
    columns,
    cross3,
    dot3,
    plane_link_part,
    point_mass,
    rod,
    stack_bodies,
    translating_part,
)
from .mass_params import G_CM2, MOMENTS, check_mass_params, link_frames, mass_param_info, translating
from .validation import as_points, choice, finite_angles, optional_positive_vector, positive_finite, positive_vector

ACTUATORS = ("theta_0", "p1", "p2")
#: The mass model's bodies with a ``link_masses`` entry: the turret (everything turning with
#: ``theta_0``: motors, housing), then four uniform rods; the handle is ``handle_mass``.
LINKS = ("turret", "proximal_1", "proximal_2", "distal_1", "distal_2")
BASE_BRANCHES = ("nearest", "front", "back")
_DEG = np.pi / 180.0
_QUARTER = np.pi / 2.0


@dataclass(frozen=True, slots=True)
class Inverse3Params:
    """Geometry (m), actuators and limits (rad) of the Inverse3 prototype (paper 000 Tables 1, 2)."""

    proximal_length: float = 0.140
    distal_length: float = 0.165
    base_height: float = 0.18645
    shoulder_offset: float = 0.04193
    tool_offset: float = 0.06423
    motor_torques: tuple[float, float, float] = (0.1, 0.1, 0.1)
    gear_ratios: tuple[float, float, float] = (6.875, 5.957, 5.957)
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    lower_limits: tuple[float, float, float] = (-205 * _DEG, 5 * _DEG, -85 * _DEG)
    upper_limits: tuple[float, float, float] = (45 * _DEG, 225 * _DEG, 114 * _DEG)
    min_link_spread: float = 20 * _DEG
    max_link_spread: float = 200 * _DEG
    body_radius: float = 0.065
    body_height: float = 0.180
    base_branch: str = "nearest"
    #: One encoder count of each joint, joint side (rad): paper 000 Table 2's resolution column.
    joint_resolution: tuple[float, float, float] = (0.0256 * _DEG, 0.0339 * _DEG, 0.0339 * _DEG)
    #: Mass model (``kinematics.mass_params``), kg and kg m^2: the turret turns about the base axis
    #: with principal moments ``turret_inertia`` about its centre on that axis; the links are uniform
    #: rods; the handle a point mass at P; rotor inertias motor side. Estimates
    #: (``resources/presets/inverse3_prototype.toml``), off by default: paper 000 gives no masses.
    link_masses: tuple[float, ...] = (0.6, 0.0131, 0.0131, 0.0154, 0.0154)
    turret_inertia: tuple[float, float, float] = (6e-4, 6e-4, 9e-4)
    handle_mass: float = 0.03
    rotor_inertias: tuple[float, float, float] = (5e-6, 5e-6, 5e-6)
    mass_model: str = "none"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, ACTUATORS, scalars=("handle_mass",), moments=("turret_inertia",))
        for name, unit in (("proximal_length", "m"), ("distal_length", "m"), ("base_height", "m"),
                           ("shoulder_offset", "m"), ("tool_offset", "m"), ("body_radius", "m"),
                           ("body_height", "m"), ("min_link_spread", "rad"), ("max_link_spread", "rad")):
            set_(self, name, positive_finite(name, getattr(self, name), unit))
        set_(self, "motor_torques", positive_vector("motor_torques", self.motor_torques, ACTUATORS, "N m"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ACTUATORS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ACTUATORS, "rad/s"))
        set_(self, "joint_resolution", positive_vector("joint_resolution", self.joint_resolution, ACTUATORS, "rad"))
        set_(self, "lower_limits", finite_angles("lower_limits", self.lower_limits, ACTUATORS))
        set_(self, "upper_limits", finite_angles("upper_limits", self.upper_limits, ACTUATORS))
        for label, lo, hi in zip(ACTUATORS, self.lower_limits, self.upper_limits):
            if not lo < hi:
                raise ValueError(f"lower_limits[{label}] must be below upper_limits[{label}], got {lo} >= {hi}")
        if not self.min_link_spread < self.max_link_spread:
            raise ValueError(
                f"min_link_spread must be below max_link_spread, got {self.min_link_spread} >= {self.max_link_spread}"
            )
        choice("base_branch", self.base_branch, BASE_BRANCHES)

    @property
    def plane_offset(self) -> float:
        """Distance of the five-bar plane from the base axis, ``tool_offset - shoulder_offset`` (m).

        Returns
        -------
        float
            m.

        Examples
        --------
        >>> round(Inverse3Params().plane_offset, 6)
        0.0223
        """
        return self.tool_offset - self.shoulder_offset


class Inverse3(MechanismBase):
    """Inverse3 prototype: base joint plus a coaxial five-bar, ``q = (theta_0, theta_p1, theta_p2)``."""

    n_joints = 3
    task_dim = 3
    joint_names = ACTUATORS
    task_names = ("x", "y", "z")
    PARAM_INFO = (
        ParamInfo("proximal_length", "mm", 1e-3, "Proximal link length l1, motor to elbow"),
        ParamInfo("distal_length", "mm", 1e-3, "Distal link length l2, elbow to the wrist point"),
        ParamInfo("base_height", "mm", 1e-3, "Height of the motors' common axis above the base (DH d1)"),
        ParamInfo("shoulder_offset", "mm", 1e-3, "DH d2 of paper 000 Table 1"),
        ParamInfo("tool_offset", "mm", 1e-3, "Minus DH d4 of paper 000 Table 1"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous motor torque", ACTUATORS),
        ParamInfo("gear_ratios", "", 1.0, "Transmission ratio, joint / motor", ACTUATORS),
        ParamInfo("joint_resolution", "deg", _DEG, "One encoder count of the joint", ACTUATORS),
        ParamInfo("lower_limits", "deg", _DEG, "Lower joint limit (motor angle)", ACTUATORS),
        ParamInfo("upper_limits", "deg", _DEG, "Upper joint limit (motor angle)", ACTUATORS),
        ParamInfo("min_link_spread", "deg", _DEG, "Smallest |theta_p1 - theta_p2|"),
        ParamInfo("max_link_spread", "deg", _DEG, "Largest |theta_p1 - theta_p2|"),
        ParamInfo("body_radius", "mm", 1e-3, "Body constraint: radial distance must exceed this ..."),
        ParamInfo("body_height", "mm", 1e-3, "... or the height must exceed this"),
        ParamInfo("base_branch", "", 1.0, "IK branch of the base joint", choices=BASE_BRANCHES),
        *mass_param_info(LINKS, "turret on the base axis; uniform rods: proximal 1, 2, distal 1, 2", ACTUATORS),
        ParamInfo("turret_inertia", "g cm^2", G_CM2, "Turret principal moments about its centre (z: the base "
                  "axis)", MOMENTS),
        ParamInfo("handle_mass", "kg", 1.0, "Handle mass, a point at the end-effector"),
    )
    mass_coordinates = "task"

    def __init__(self, params: Inverse3Params | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else Inverse3Params(**kwargs))

    # -- mass model -------------------------------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """The turret, four uniform rods (x along the link from its motor-side joint) and the handle."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        l1, l2 = p.proximal_length, p.distal_length
        turret = Body("turret", p.link_masses[0], (0.0, 0.0, 0.0), (*p.turret_inertia, 0.0, 0.0, 0.0))
        rods = tuple(rod(name, m, length) for name, m, length in zip(LINKS[1:], p.link_masses[1:], (l1, l1, l2, l2)))
        return (turret, *rods, point_mass("handle", p.handle_mass))

    @property
    def revolution(self) -> tuple[float, float, float]:
        """The base joint's range and the five-bar plane's offset from its axis: the (x, z) map
        slice revolved over it is the workspace."""
        p = self.params
        return p.lower_limits[0], p.upper_limits[0], p.plane_offset

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame, (..., 6, 3, 3) and (..., 6, 3), m.

        The turret turns by ``theta_0`` about z, its centre on the motors' axis; the five-bar
        plane has the radial axis ``e_r = (cos th0, sin th0, 0)`` and normal ``n = (-sin th0,
        cos th0, 0)``, the motors' common centre ``O = base_height z + plane_offset n``, and each
        elbow ``O + l1 (cos phi_i e_r + sin phi_i z)`` with ``phi_i = theta_pi - 90 deg``.
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        q, x = as_points("q", q, 3), as_points("x", x, 3)
        q, x = np.broadcast_arrays(q, x)
        p = self.params
        th0 = q[..., 0]
        zero, one = np.zeros_like(th0), np.ones_like(th0)
        c0, s0 = np.cos(th0), np.sin(th0)
        radial = np.stack([c0, s0, zero], -1)
        normal = np.stack([-s0, c0, zero], -1)
        up = np.stack([zero, zero, one], -1)
        centre = p.base_height * up + p.plane_offset * normal
        phi = q[..., 1:] - _QUARTER
        elbows = [centre + p.proximal_length * (np.cos(phi[..., i, None]) * radial + np.sin(phi[..., i, None]) * up)
                  for i in range(2)]
        turret = np.stack([radial, normal, up], axis=-1)
        starts = [centre, centre, elbows[0], elbows[1]]
        ends = [elbows[0], elbows[1], x, x]
        rot = [turret, *(link_frames(a, b, normal) for a, b in zip(starts, ends)), translating(th0.shape)]
        origins = [p.base_height * up, *starts, x]
        return np.stack(rot, axis=-3), np.stack(origins, axis=-2)

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (6, 3, 3, N), ``R_b`` (6, 3, 3, N) and ``G = dq/dx = J^-1`` (3, 3, N).

        Component-first (``kinematics.bodies``). The turret turns at ``dtheta_0 = G_0 xdot`` about
        z, so ``e_r' = n dtheta_0``, ``n' = -e_r dtheta_0``; elbow i moves with the turret and at
        ``l1 (-sin phi_i e_r + cos phi_i z) G_i xdot`` in the five-bar plane.
        """
        q, x = as_points("q", q, 3).reshape(-1, 3), as_points("x", x, 3).reshape(-1, 3)
        p = self.params
        # J^-1 by its adjugate: its rows are the cross products of J's columns over det J.
        jac = np.moveaxis(self.jacobian(q), 0, -1)                                          # (3, 3, N)
        cols = [jac[:, c] for c in range(3)]
        g = np.stack([cross3(cols[(u + 1) % 3], cols[(u + 2) % 3]) for u in range(3)])
        g /= dot3(cols[0], g[0])
        q, x = columns(q), columns(x)
        n = q.shape[-1]
        zero, one = np.zeros(n), np.ones(n)
        c0, s0 = np.cos(q[0]), np.sin(q[0])
        radial, normal, up = np.stack([c0, s0, zero]), np.stack([-s0, c0, zero]), np.stack([zero, zero, one])
        dradial, dnormal = normal[:, None] * g[0], -radial[:, None] * g[0]
        centre = p.base_height * up + p.plane_offset * normal
        dcentre = p.plane_offset * dnormal
        elbows, delbows = [], []
        for i in (1, 2):
            cphi, sphi = np.cos(q[i] - _QUARTER), np.sin(q[i] - _QUARTER)
            elbows.append(centre + p.proximal_length * (cphi * radial + sphi * up))
            delbows.append(dcentre + p.proximal_length * (cphi * dradial + (cphi * up - sphi * radial)[:, None] * g[i]))
        dx = np.zeros((3, 3, n))
        dx[0, 0] = dx[1, 1] = dx[2, 2] = 1.0
        still = np.zeros((3, 3, n))
        turret = (np.stack([radial, normal, up], axis=1), up[:, None] * g[0], still)      # turns about z
        # The five-bar plane turns with the turret: its links at the turret's rate plus their own in-plane one.
        links = [plane_link_part(a, b, normal, da, db, turret[1]) for a, b, da, db in
                 zip([centre, centre, *elbows], [*elbows, x, x], [dcentre, dcentre, *delbows], [*delbows, dx, dx])]
        jv, jw, rot = stack_bodies([turret, *links, translating_part(dx)], body_arrays(self.bodies())[1])
        return jv, jw, rot, g

    # -- five-bar part --------------------------------------------------------------------
    def _reach(self, h: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``a3(h)`` and ``d a3 / d h`` of the coaxial five-bar."""
        l1, l2 = self.params.proximal_length, self.params.distal_length
        sin_h, cos_h = np.sin(h), np.cos(h)
        root = np.sqrt(np.maximum(l2 * l2 - (l1 * sin_h) ** 2, 0.0))
        a3 = l1 * cos_h + root
        with np.errstate(divide="ignore", invalid="ignore"):
            da3 = -l1 * sin_h * (1.0 + l1 * cos_h / root)
        return a3, da3

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """End-effector ``P`` (..., 3) in m for joints ``q`` (..., 3), and whether it assembles.

        Examples
        --------
        >>> x, ok = Inverse3().forward([[0.0, 2.0, 1.0], [0.1, 2.0, 1.0]])
        >>> x.shape, ok.tolist()
        ((2, 3), [True, True])
        """
        q = as_points("q", q, 3)
        with np.errstate(invalid="ignore"):          # non-finite q: nan throughout, not ok
            th0 = q[..., 0]
            phi1, phi2 = q[..., 1] - _QUARTER, q[..., 2] - _QUARTER
            th3, h = 0.5 * (phi1 + phi2), 0.5 * (phi1 - phi2)
            l1, l2 = self.params.proximal_length, self.params.distal_length
            ok = (l1 * np.sin(h)) ** 2 <= l2 * l2
            a3, _ = self._reach(h)
            u, w = a3 * np.cos(th3), a3 * np.sin(th3)
            c = self.params.plane_offset
            cos0, sin0 = np.cos(th0), np.sin(th0)
            p = np.stack([u * cos0 - c * sin0, u * sin0 + c * cos0, self.params.base_height + w], axis=-1)
        return np.where(ok[..., None], p, np.nan), ok

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J = dP/dq`` (..., 3, 3) in m/rad, without gear ratios (``xdot = J qdot``).

        ``x`` (the pose of ``q``) is accepted for the contract and not needed: J depends on ``q`` only.

        Examples
        --------
        >>> Inverse3().jacobian(np.zeros((4, 5, 3))).shape
        (4, 5, 3, 3)
        """
        q = as_points("q", q, 3)
        th0 = q[..., 0]
        phi1, phi2 = q[..., 1] - _QUARTER, q[..., 2] - _QUARTER
        th3, h = 0.5 * (phi1 + phi2), 0.5 * (phi1 - phi2)
        a3, da3 = self._reach(h)
        cos3, sin3 = np.cos(th3), np.sin(th3)
        u = a3 * cos3
        c = self.params.plane_offset
        cos0, sin0 = np.cos(th0), np.sin(th0)
        # d(u, w)/d th3 = (-w, u) and d(u, w)/d h = da3 (cos3, sin3); dth3 = dh = 1/2 for p1,
        # dth3 = 1/2, dh = -1/2 for p2.
        du_th3, dw_th3 = -a3 * sin3, a3 * cos3
        du_h, dw_h = da3 * cos3, da3 * sin3
        du1, dw1 = 0.5 * (du_th3 + du_h), 0.5 * (dw_th3 + dw_h)
        du2, dw2 = 0.5 * (du_th3 - du_h), 0.5 * (dw_th3 - dw_h)
        # Filled entry by entry in (3, 3, ...) layout and returned as a (..., 3, 3) view:
        # metrics.linalg.components() then gets its contiguous entry arrays without a copy.
        jac = np.empty((3, 3) + q.shape[:-1])
        jac[0, 0] = -u * sin0 - c * cos0
        jac[1, 0] = u * cos0 - c * sin0
        jac[2, 0] = 0.0
        jac[0, 1], jac[1, 1], jac[2, 1] = du1 * cos0, du1 * sin0, dw1
        jac[0, 2], jac[1, 2], jac[2, 2] = du2 * cos0, du2 * sin0, dw2
        return np.moveaxis(jac, (0, 1), (-2, -1))

    def inverse(self, x: ArrayLike, base_branch: str | None = None) -> tuple[FloatArray, BoolArray]:
        """Joint angles ``q`` (..., 3) reaching ``x`` (..., 3) in m, and ``reachable`` (...).

        ``base_branch``: the base joint reaches a point from the front (radial coordinate
        ``u >= 0``) or from the back (``u < 0``); ``"nearest"`` takes the one with the smaller
        ``|theta_0|``, so a slice at ``theta_0 = 0`` is swept without turning the base. Motor
        angles are shifted by the same multiple of 360 deg so that ``theta_p1`` lies in its
        limits where it can. Unreachable points get ``nan`` (limits are checked by ``feasible``).

        Examples
        --------
        >>> mech = Inverse3()
        >>> x, _ = mech.forward([0.0, 2.0, 1.0])
        >>> q, ok = mech.inverse(x)
        >>> bool(np.allclose(q, [0.0, 2.0, 1.0], rtol=0.0, atol=1e-12)), bool(ok)
        (True, True)
        """
        branch = choice("base_branch", base_branch or self.params.base_branch, BASE_BRANCHES)
        x = as_points("x", x, 3)
        c = self.params.plane_offset
        l1, l2 = self.params.proximal_length, self.params.distal_length
        # reshape: ascontiguousarray makes a single point's 0-d coordinates 1-d.
        x0 = np.ascontiguousarray(x[..., 0]).reshape(x.shape[:-1])
        x1 = np.ascontiguousarray(x[..., 1]).reshape(x.shape[:-1])
        horizontal_sq = x0 * x0 + x1 * x1
        radial_sq = horizontal_sq - c * c
        reach_ok = radial_sq >= -8 * np.finfo(float).eps * (horizontal_sq + c * c)
        u_abs = np.sqrt(np.maximum(radial_sq, 0.0))
        azimuth = np.arctan2(x1, x0)
        beta = np.arctan2(c, u_abs)           # in (0, pi/2]: the back branch turns by pi - beta
        th0_front = _wrap_pi(azimuth - beta)
        if branch == "front":
            back = np.zeros(x.shape[:-1], bool)
        elif branch == "back":
            back = np.ones(x.shape[:-1], bool)
        else:
            back = np.abs(_wrap_pi(azimuth + beta - np.pi)) < np.abs(th0_front)
        th0 = np.where(back, azimuth + beta - np.pi, th0_front)
        u = np.where(back, -u_abs, u_abs)
        w = x[..., 2] - self.params.base_height
        a3 = np.hypot(u, w)
        th3 = np.arctan2(w, u)
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_h = (l1 * l1 + a3 * a3 - l2 * l2) / (2.0 * l1 * a3)
        slack_h = 8 * np.finfo(float).eps
        reach_ok &= np.abs(cos_h) <= 1.0 + slack_h
        h = np.arccos(np.clip(cos_h, -1.0, 1.0))
        p1 = th3 + h + _QUARTER
        p2 = th3 - h + _QUARTER
        p1_wrapped, _ = wrap_into(p1, self.params.lower_limits[1], self.params.upper_limits[1])
        shift = p1_wrapped - p1
        th0_wrapped, _ = wrap_into(th0, self.params.lower_limits[0], self.params.upper_limits[0])
        q = np.stack([th0_wrapped, p1 + shift, p2 + shift], axis=-1)
        if not reach_ok.all():
            q[~reach_ok] = np.nan
        return q, reach_ok

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Table 2 joint limits, link spread and the body constraint, shape (...).

        ``x`` (the pose of ``q``) is computed when not given. The body constraint reads
        ``radial > body_radius or z > body_height`` with ``radial`` the in-plane distance
        from the base axis (the paper's ``P_x`` on the ``theta_0 = 0`` slice).
        """
        q = as_points("q", q, 3)
        p = self.params
        with np.errstate(invalid="ignore"):
            ok = np.all(np.isfinite(q), axis=-1)
            for i in range(3):
                ok &= (q[..., i] >= p.lower_limits[i]) & (q[..., i] <= p.upper_limits[i])
            spread = np.abs(q[..., 1] - q[..., 2])
            ok &= (spread >= p.min_link_spread) & (spread <= p.max_link_spread)
            if x is None:
                x, _ = self.forward(q)
            x = np.asarray(x, float)
            cos0, sin0 = np.cos(q[..., 0]), np.sin(q[..., 0])
            radial = x[..., 0] * cos0 + x[..., 1] * sin0
            ok &= (radial > p.body_radius) | (x[..., 2] > p.body_height)
        return ok

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline base -> column top -> plane centre -> elbow 1 -> P -> elbow 2 -> centre, (..., 7, 3)."""
        q = as_points("q", q, 3)
        p = self.params
        th0 = q[..., 0]
        phi = q[..., 1:] - _QUARTER
        end, _ = self.forward(q)
        cos0, sin0 = np.cos(th0), np.sin(th0)
        c = p.plane_offset

        def plane_point(u, w):
            return np.stack([u * cos0 - c * sin0, u * sin0 + c * cos0, p.base_height + w], axis=-1)

        zero = np.zeros_like(th0)
        base = np.stack([zero, zero, zero], axis=-1)
        column = np.stack([zero, zero, zero + p.base_height], axis=-1)
        centre = plane_point(zero, zero)
        l1 = p.proximal_length
        elbow1 = plane_point(l1 * np.cos(phi[..., 0]), l1 * np.sin(phi[..., 0]))
        elbow2 = plane_point(l1 * np.cos(phi[..., 1]), l1 * np.sin(phi[..., 1]))
        return np.stack([base, column, centre, elbow1, end, elbow2, centre], axis=-2)


def _wrap_pi(angle: FloatArray) -> FloatArray:
    """Angle wrapped into [-pi, pi)."""
    return angle - 2.0 * np.pi * np.floor((angle + np.pi) / (2.0 * np.pi))
