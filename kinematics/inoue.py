"""Inoue platform: a 6-DOF platform on three waist-mounted five-bar legs (paper 001, sec. V).

One module over the ~600-line guide on purpose: the reconstructed geometry, the legs' inverse
kinematics, the platform Jacobian, the feasibility tests and the body frames all read the one
list of reconstruction choices below, which a reader checks against the paper in one place.

Paper 001 compares the Twin-Pantograph with "the Inoue platform [6]" (Collins and Long's
in-parallel hand controller; Long and Collins' pantograph platform, its [18]): a platform
held by three pantograph (five-bar) linkages whose actuators sit in the base. Its Fig. 10 is
not in our text and neither source is at hand, so the geometry below is a reconstruction
from what paper 001 says; every choice is a parameter or is listed here.

What the text fixes
-------------------
* Six actuators, a square 6 x 6 Jacobian (sec. V: "all three manipulators have square (i.e.
  6x6) Jacobian matrices"), two per five-bar; U-joints join the five-bars to the platform and
  may be limited to +-85 deg "to avoid a spherical wrist singularity" (as the Twin-Pantograph's).
* The footnote: "the same redundant actuation and sensing approach can be used with the Inoue
  platform", i.e. the Twin-Pantograph's actuated waist. So each leg is one Twin-Pantograph
  unit (waist joint + five-bar in the plane the waist turns) with a *passive* waist; parameter
  ``waist_actuators = "active"`` adds the three waists as redundant actuators (6 x 9).
* Table V's design space ``l1..l7, eta1, eta2, Q1, Q2``, shared in part with the Twin-Pantograph
  (``l1..l4, l6``) and the Stewart platform (``l1, l4..l7, eta1, eta2``), and eq. 18:
  ``S_J = diag(1, 1, Q1, Q2, Q2, Q1)`` "since the devices are symmetric about the jk plane but
  not about the ik plane".

Our reading (reconstructed)
---------------------------
* Frame = the paper's ``(i, j, k)`` as ``(x, y, z)``; the base in ``z = 0``; the workspace along
  ``+z`` (25 cm in the paper's comparison). Symmetric about the ``jk`` plane (``x = 0``).
* ``l1`` shoulder separation, ``l2`` upper arm, ``l3`` forearm of every five-bar (Table V's
  ranges 1-5, 12-22, 20-30 cm match the Twin-Pantograph's ``l1..l3``).
* Base: leg 1's waist centre at radius ``l4`` on azimuth 90 deg (on ``+y``), legs 2 and 3 at
  radius ``l5`` on azimuths ``90 +- eta1``. Platform: attachment 1 at radius ``l6`` on azimuth
  90 deg, attachments 2 and 3 at radius ``l7`` on ``90 +- eta2``, in the platform plane, whose
  origin is the task point (the paper's ``o_p``, no tool offset). Leg ``k`` holds attachment
  ``k``. Two radii and an angle are the three numbers of a triangle symmetric about ``x = 0``
  placed relative to the origin; with ``eta = 120 deg`` and equal radii it is equilateral.
  Table V's optimum (``eta2 = 170 deg``, ``l6 = 2``, ``l7 = 4`` cm) is then a slim triangle
  along ``j``, the axis of Table I's smallest moment (0.5 cm), which is what one expects an
  optimizer to find.
* Leg ``k`` (azimuth ``phi_k``): radial ``e_rad = (cos phi, sin phi, 0)``, tangential
  ``e_t = (-sin phi, cos phi, 0)``. The waist axis is ``e_t`` through the waist centre
  ``B_k``; the waist angle ``psi`` turns the five-bar plane about it, spanned by ``e_t`` and
  ``e_r(psi) = cos psi e_z + sin psi e_rad`` (``psi > 0`` leans outwards), normal
  ``n = e_t x e_r``. Shoulders on the waist axis at ``B_k -+ (l1/2) e_t``: the first actuator of
  the leg (``q1``, ``q3``, ``q5``) at ``-l1/2``. The mirror ``x -> -x`` swaps ``q1 <-> q2``,
  ``q3 <-> q6``, ``q4 <-> q5``: eq. 18's pairs. Shoulder angles as in ``kinematics.fivebar``
  (from ``+e_t`` towards ``+e_r``); IK branch: waist "front" (tip at ``+e_r``), elbows outward
  (``FiveBar`` working mode ``"+-"``); FK assembly: tip beyond the elbows (``"up"``).
* U-joints: the leg-side shaft is the plane normal ``n_k`` (a pin through the five-bar's tip
  joint, so tip joint + U-joint form a spherical wrist), the platform-side shaft is fixed in
  the platform along ``R e_rad(phi_k)``. The bend is ``angle(n_k, R e_rad(phi_k))`` (0 with the
  plane upright at zero orientation), limited to ``ujoint_limit``; at 90 deg the wrist's three
  axes are coplanar. That singularity is a passive one: the actuated rates do not see it (the
  shoulders' rates depend only on the tips' velocities), so only the limit excludes it.
* Actuator scale factors: ``Q1``, ``Q2`` are ratios of ``motor_torques`` (``q3 = q6 = Q1 q1``,
  ``q4 = q5 = Q2 q1``, ``actuator_scales``). They are not separate parameters because every
  evaluator takes the torque limit as ``motor_torques * gear_ratios``; a study varies a pair by
  targeting both entries (``Q1 = { targets = ["motor_torques.q3", "motor_torques.q6"], ... }``).
* Paper 001 gives no joint ranges: the defaults are wide (waists +-90 deg, shoulders over
  270 deg, as the Twin-Pantograph's) and only the U-joint bend is the paper's. Link widths,
  joint offsets and collisions are not modelled. GII values are therefore not expected to
  reproduce the paper's 0.215 (Table V); trends can be compared. What we get for Table V's
  design (force-map GII, human-hand ``S_T``, end-effector frame, on the paper's half workspace
  ``i >= 0``, ``+-5 cm`` in ``j, k`` at 25 cm, tilt 30 deg about the ``j`` tool axis, rolls
  +-30 deg): 0.198 on 11,875 samples (25 mm steps, 2 rings, 5 rolls), 0.199 on 188,811 (10 /
  12.5 mm, 3 rings, 7 rolls). That it is near 0.215 is not evidence the geometry is the paper's.

Coordinates, Jacobian, statics
------------------------------
``x = (x, y, z, rx, ry, rz)``: the platform origin (m) and the rotation vector of the platform
(rad, base frame). Leg ``k``'s tip velocity is ``Tdot_k = v + omega x a_k`` (``a_k = R p_k``), so
with the twist ``xi = [v; omega]`` the shoulder ``j`` rate is ``g . Tdot_k`` with
``g = D_j / (l2 d_j . t_j)`` (``D_j`` the 3D distal vector, ``d_j``, ``t_j`` its in-plane form
and the upper arm's tangent; from ``|T - E_j| = l3``), a row ``[g, a_k x g]`` of ``K``
(``qdot = K xi``); a waist's rate is ``n . Tdot_k / w`` (``w`` the tip's distance from the waist
axis). ``jacobian`` is ``J = K^-1`` (redundant: ``K^+``), ``force_map`` ``A = K^T``: the wrench
``w = [f; m]`` (N; N m about the platform origin, base frame) held by joint torques ``tau``.
FK: each five-bar fixes its tip in its plane, so only the three waists are unknown; Newton on
the pose against the tips' in-plane coordinates (closed form from the three tips for active
waists, with a consistency check); see ``forward`` for the choice of assembly.

Over 600 lines for a stated reason: one model class whose IK, K rows, FK and limits share the
private ``_Config`` structure, and about half the file is docstrings (this reconstruction's
description and the numpydoc sections); the code is about 300 lines.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .actuated import ActuatedSubset
from .angles import wrap_into
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, joint_side, memoised, singular_limit
from .bodies import Body, body_arrays, columns, cross3, dot3, plane_link_part, point_mass, rod, stack_bodies
from .fivebar import FiveBar
from .mass_params import G_CM2, MOMENTS, check_mass_params, link_frames, mass_param_info
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
from .validation import as_points, choice, finite_angles, optional_positive_vector, positive_finite, positive_vector
from .vector_rows import angle_between as row_angle
from .vector_rows import dot as row_dot

#: Shoulders q1..q6 (leg 1: q1, q2; leg 2: q3, q4; leg 3: q5, q6), then the waists w1..w3.
ALL_JOINTS = ("q1", "q2", "q3", "q4", "q5", "q6", "w1", "w2", "w3")
MODES = ("passive", "active")
#: The mass model's parts (``link_masses``, kg): per leg the waist body (the shoulder motors turning
#: with the waist), each upper arm and forearm (uniform rods), each elbow and the tip joint (point
#: masses), each shoulder's counterweight (a point ``counterweight_offset`` behind the shoulder on the
#: upper arm's extension), as ``kinematics.twin_pantograph``; then the platform (with the grip).
LINKS = ("waist", "upper_arm", "forearm", "elbow", "tip", "counterweight", "platform")
_DEG = np.pi / 180.0
_EPS = np.finfo(np.float64).eps
_EZ = np.array([0.0, 0.0, 1.0])
#: FK stops when every tip's in-plane coordinates ``(u, w)`` are within ``FK_RTOL * S`` of the
#: five-bars' (``S`` the device size, ``InouePlatform.size``). Derivation (``u = eps / 2``; every
#: vector below is bounded by ``S``): ``d = o + R p_k - B_k`` costs ``gamma_3 sqrt(3) |p|`` (``R p``)
#: ``+ 2 u S`` (two additions), ``u = d . e_t`` and ``w = hypot(d_z, d . e_rad)`` another ``~4 u S``:
#: ~15 u S ~ 7.5 eps S; the stored iterate (``o + dv``, ``exp([dw]x) R``) ~3 eps S as in
#: ``kinematics.stewart``; the five-bar's tip (elbows, chord midpoint, square root) ~4 eps S.
#: So ~15 eps S at the nearest representable pose; 24 eps S is attainable on every path and
#: still 1e-15 m on the 0.47 m default.
FK_RTOL = 24 * _EPS
#: A converged FK is the model's branch if IK of its pose gives the joints back within this
#: (rad): a wrong branch differs by 0.1-1 rad, the right one by rounding times the condition
#: number (1e-16 x 1e6 even close to a singularity).
BRANCH_TOL = 1e-8
#: Joint-path steps of the FK fallback (``InouePlatform._continuation``).
CONTINUATION_STEPS = 8
#: Largest turn (rad) of one FK Newton step (``InouePlatform._newton``).
MAX_TURN = 0.25


@dataclass(frozen=True, slots=True)
class InoueParams:
    """Geometry (m, rad), actuators, limits (rad) and actuation of an Inoue platform.

    Defaults: paper 001 Table V's optimum (l1 = 2, l2 = 16, l3 = 24, l4 = l5 = 2, l6 = 2,
    l7 = 4 cm, eta1 = 120, eta2 = 170 deg, Q1 = Q2 = 0.75) with shoulder motors of 0.1 N m
    (illustrative: the paper gives only ratios), waists passive, U-joints limited to 85 deg.
    """

    shoulder_separation: float = 0.02
    upper_arm: float = 0.16
    forearm: float = 0.24
    base_apex_radius: float = 0.02
    base_pair_radius: float = 0.02
    platform_apex_radius: float = 0.02
    platform_pair_radius: float = 0.04
    base_pair_angle: float = 120 * _DEG
    platform_pair_angle: float = 170 * _DEG
    ujoint_limit: float = 85 * _DEG
    motor_torques: tuple[float, ...] = (0.1, 0.1, 0.075, 0.075, 0.075, 0.075, 0.1, 0.1, 0.1)
    gear_ratios: tuple[float, ...] = (1.0,) * 9
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    lower_limits: tuple[float, ...] = (0.0, -90 * _DEG) * 3 + (-90 * _DEG,) * 3
    upper_limits: tuple[float, ...] = (270 * _DEG, 180 * _DEG) * 3 + (90 * _DEG,) * 3
    waist_actuators: str = "passive"
    #: Mass model (``kinematics.mass_params``), kg, kg m^2 and m, every leg alike: see ``LINKS`` and
    #: ``InouePlatform.bodies``. ``waist_inertia``: the waist body's principal moments about its
    #: centre (x: the waist axis, y: the in-plane radial direction, z: the plane normal);
    #: ``platform_inertia``: the platform's about its centre of mass, the centroid of the three
    #: attachments (platform axes). Rotor inertias motor side, one per joint (the actuated ones are
    #: used). Estimates of ``resources/presets/inoue_platform.toml``, off by default.
    link_masses: tuple[float, ...] = (0.72, 0.00724, 0.01086, 0.0247, 0.0346, 0.285, 0.0113)
    waist_inertia: tuple[float, float, float] = (17600 * G_CM2, 18600 * G_CM2, 2180 * G_CM2)
    platform_inertia: tuple[float, float, float] = (75.8 * G_CM2, 70.4 * G_CM2, 5.86 * G_CM2)
    counterweight_offset: float = 0.035
    rotor_inertias: tuple[float, ...] = (68.1 * G_CM2,) * 9
    mass_model: str = "none"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, ALL_JOINTS, moments=("waist_inertia", "platform_inertia"))
        set_(self, "counterweight_offset", positive_finite("counterweight_offset", self.counterweight_offset, "m"))
        for name in ("shoulder_separation", "upper_arm", "forearm", "base_apex_radius", "base_pair_radius",
                     "platform_apex_radius", "platform_pair_radius"):
            set_(self, name, positive_finite(name, getattr(self, name), "m"))
        for name in ("base_pair_angle", "platform_pair_angle"):       # open: 0 or 180 deg merges legs
            set_(self, name, angle_in(name, getattr(self, name), 0.0, np.pi))
        set_(self, "ujoint_limit", angle_in("ujoint_limit", self.ujoint_limit, 0.0, np.pi / 2, open_lower=True))
        set_(self, "motor_torques", positive_vector("motor_torques", self.motor_torques, ALL_JOINTS, "N m"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ALL_JOINTS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ALL_JOINTS, "rad/s"))
        set_(self, "lower_limits", finite_angles("lower_limits", self.lower_limits, ALL_JOINTS))
        set_(self, "upper_limits", finite_angles("upper_limits", self.upper_limits, ALL_JOINTS))
        for label, lo, hi in zip(ALL_JOINTS, self.lower_limits, self.upper_limits):
            if not lo < hi:
                raise ValueError(f"lower_limits[{label}] must be below upper_limits[{label}], got {lo} >= {hi}")
            if hi - lo > 2 * np.pi + 1e-12:
                raise ValueError(f"upper_limits[{label}] - lower_limits[{label}] must be at most 360 deg, "
                                 f"got {np.degrees(hi - lo):g} deg")
        choice("waist_actuators", self.waist_actuators, MODES)


class _Geometry(NamedTuple):
    """Fixed vectors of the three legs (row k = leg k), m and unit vectors."""

    e_rad: FloatArray      # (3, 3) radial direction of the leg's azimuth
    e_t: FloatArray        # (3, 3) tangential: the waist axis
    base: FloatArray       # (3, 3) waist centres B_k
    attach: FloatArray     # (3, 3) platform attachments p_k, platform frame


class _Config(NamedTuple):
    """Everything a pose fixes (IK branch of the model), per leg on axis -2 (or -3 for in-plane pairs)."""

    rot: FloatArray        # (..., 3, 3) platform rotation R
    arm: FloatArray        # (..., 3, 3) R p_k
    tips: FloatArray       # (..., 3, 3) U-joint centres T_k
    psi: FloatArray        # (..., 3) waist angles
    w: FloatArray          # (..., 3) tip distance from the waist axis (> 0)
    er: FloatArray         # (..., 3, 3) in-plane radial direction e_r(psi)
    n: FloatArray          # (..., 3, 3) plane normal
    theta: FloatArray      # (..., 3, 2) shoulder angles
    distal: FloatArray     # (..., 3, 2, 2) in-plane distal vectors tip - elbow
    tangent: FloatArray    # (..., 3, 2, 2) in-plane d(cos, sin)/d theta
    ok: BoolArray          # (...) every leg reaches


#: The last configuration (``_config``) and singularity classes each thread computed, keyed on
#: the model and the exact poses (``kinematics.pose_memo``).
_LAST_CONFIG = PoseMemo()
_LAST_SINGULARITY = PoseMemo()


class InouePlatform(ActuatedSubset, MechanismBase):
    """Inoue platform: three passive-waist five-bar legs holding a platform (paper 001). See the module doc."""

    task_dim = 6
    task_names = ("x", "y", "z", "rx", "ry", "rz")
    task_units = ("m", "m", "m", "rad", "rad", "rad")
    singularity_classes = ("none", "inverse", "direct")
    PARAM_INFO = (
        ParamInfo("shoulder_separation", "mm", 1e-3, "l1: distance between a leg's two shoulder joints"),
        ParamInfo("upper_arm", "mm", 1e-3, "l2: proximal (upper arm) link length of each leg"),
        ParamInfo("forearm", "mm", 1e-3, "l3: distal (forearm) link length of each leg"),
        ParamInfo("base_apex_radius", "mm", 1e-3, "l4: radius of leg 1's waist centre (azimuth 90 deg)"),
        ParamInfo("base_pair_radius", "mm", 1e-3, "l5: radius of legs 2 and 3's waist centres"),
        ParamInfo("platform_apex_radius", "mm", 1e-3, "l6: radius of platform attachment 1 (azimuth 90 deg)"),
        ParamInfo("platform_pair_radius", "mm", 1e-3, "l7: radius of platform attachments 2 and 3"),
        ParamInfo("base_pair_angle", "deg", _DEG, "eta1: azimuth of legs 2, 3 from leg 1 (+- about z)"),
        ParamInfo("platform_pair_angle", "deg", _DEG, "eta2: azimuth of attachments 2, 3 from attachment 1"),
        ParamInfo("ujoint_limit", "deg", _DEG, "Largest U-joint bend (plane normal vs. platform shaft)"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous motor torque (Q1 = q3/q1 = q6/q1, Q2 = q4/q1 = q5/q1)",
                  ALL_JOINTS),
        ParamInfo("gear_ratios", "", 1.0, "Transmission ratio, joint / motor", ALL_JOINTS),
        ParamInfo("lower_limits", "deg", _DEG, "Lower joint limit", ALL_JOINTS),
        ParamInfo("upper_limits", "deg", _DEG, "Upper joint limit", ALL_JOINTS),
        ParamInfo("waist_actuators", "", 1.0, "Waists w1..w3: passive (6 x 6) or actuated (redundant, 6 x 9)",
                  choices=MODES),
        *mass_param_info(LINKS, "per leg: waist body, each upper arm, forearm (rods), elbow, tip joint, "
                         "counterweight (points); the platform with its grip", ALL_JOINTS),
        ParamInfo("waist_inertia", "g cm^2", G_CM2, "Waist body's principal moments about its centre on the "
                  "waist axis (x: the waist axis)", MOMENTS),
        ParamInfo("platform_inertia", "g cm^2", G_CM2, "Platform's principal moments about its centre of mass "
                  "(the attachments' centroid), platform axes", MOMENTS),
        ParamInfo("counterweight_offset", "mm", 1e-3, "Counterweight's distance behind the shoulder, on the "
                  "upper arm's extension"),
    )
    mass_coordinates = "task"

    def __init__(self, params: InoueParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else InoueParams(**kwargs))
        p = self.params
        phi = np.array([90 * _DEG, 90 * _DEG + p.base_pair_angle, 90 * _DEG - p.base_pair_angle])
        rad = np.array([p.base_apex_radius, p.base_pair_radius, p.base_pair_radius])
        chi = np.array([90 * _DEG, 90 * _DEG + p.platform_pair_angle, 90 * _DEG - p.platform_pair_angle])
        arm = np.array([p.platform_apex_radius, p.platform_pair_radius, p.platform_pair_radius])
        zero = np.zeros(3)
        e_rad = np.stack([np.cos(phi), np.sin(phi), zero], -1)
        e_t = np.stack([-np.sin(phi), np.cos(phi), zero], -1)
        attach = np.stack([arm * np.cos(chi), arm * np.sin(chi), zero], -1)
        object.__setattr__(self, "_geo", _Geometry(e_rad, e_t, rad[:, None] * e_rad, attach))
        object.__setattr__(self, "_planar", FiveBar(proximal=p.upper_arm, distal=p.forearm,
                                                     half_base=0.5 * p.shoulder_separation))

    # -- mass model -------------------------------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """Per leg (1, 2, 3): the waist body, upper arms, forearms (rods along x from the motor-side
        joint), elbows, counterweights and the tip joint; then the platform."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        m_waist, m_upper, m_fore, m_elbow, m_tip, m_cw, m_platform = p.link_masses
        leg = (Body("waist", m_waist, (0.0, 0.0, 0.0), (*p.waist_inertia, 0.0, 0.0, 0.0)),
               rod("upper_arm", m_upper, p.upper_arm), rod("upper_arm", m_upper, p.upper_arm),
               rod("forearm", m_fore, p.forearm), rod("forearm", m_fore, p.forearm),
               point_mass("elbow", m_elbow), point_mass("elbow", m_elbow),
               point_mass("counterweight", m_cw), point_mass("counterweight", m_cw),
               point_mass("tip", m_tip))
        centre = tuple(float(v) for v in self._geo.attach.mean(axis=0))
        platform = Body("platform", m_platform, centre, (*p.platform_inertia, 0.0, 0.0, 0.0))
        return (*leg, *leg, *leg, platform)

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame, (..., 31, 3, 3) and (..., 31, 3), m, from the pose ``x``.

        A waist body turns with its waist: axes ``(e_t, e_r, n)``, origin the waist centre ``B_k``.
        Upper arm ``j`` runs from shoulder ``j`` to elbow ``j``, forearm ``j`` from elbow ``j`` to the
        tip (``link_frames`` with the plane normal); the counterweight of shoulder ``j`` sits
        ``counterweight_offset`` behind it on the line elbow -> shoulder. The platform frame is the
        pose's ``R`` at the task point. ``q`` is not used: the bodies follow from the pose.
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        x = as_points("x", x, 6)
        cfg = self._config(x)
        g, p = self._geo, self.params
        shoulders_2d = np.array([[-0.5 * p.shoulder_separation, 0.0], [0.5 * p.shoulder_separation, 0.0]])
        elbows_2d = self._planar.elbows(cfg.theta)                                     # (..., 3, 2, 2)
        rot, org = [], []
        for k in range(3):
            et = np.broadcast_to(g.e_t[k], cfg.er[..., k, :].shape)
            er, n, tip = cfg.er[..., k, :], cfg.n[..., k, :], cfg.tips[..., k, :]

            def to3(uw, et=et, er=er, k=k):
                return g.base[k] + uw[..., 0:1] * et + uw[..., 1:2] * er

            shoulders = [to3(np.broadcast_to(s, er.shape[:-1] + (2,))) for s in shoulders_2d]
            elbows = [to3(elbows_2d[..., k, j, :]) for j in range(2)]
            back = [s - p.counterweight_offset * (e - s) / p.upper_arm for s, e in zip(shoulders, elbows)]
            waist = np.stack([et, er, n], axis=-1)
            rot += [waist, *(link_frames(s, e, n) for s, e in zip(shoulders, elbows)),
                    *(link_frames(e, tip, n) for e in elbows), waist, waist, waist, waist, waist]
            org += [np.broadcast_to(g.base[k], tip.shape), *shoulders, *elbows, *elbows, *back, tip]
        rot.append(cfg.rot)
        org.append(x[..., :3])
        rot, org = np.stack(rot, axis=-3), np.stack(org, axis=-2)
        ok = cfg.ok[..., None, None]
        return np.where(ok[..., None], rot, np.nan), np.where(ok, org, np.nan)

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (31, 3, 6, N), ``R_b`` (31, 3, 3, N) and ``G = dq/dx`` (n, 6, N).

        Component-first (``kinematics.bodies``), in the rates of the pose coordinates ``x`` (the
        position and the rotation vector, as ``body_poses`` is placed). The platform turns at
        ``omega = J_l(r) rdot``; tip k moves at ``T_k' = v + omega x R a_k``; its waist at
        ``n . T_k' / w`` and its shoulders at ``D_j . T_k' / (l2 d_j . t_j)`` (the loop closures,
        ``inverse_jacobian``'s rows). A waist body turns about ``e_t`` (``e_r' = n psidot``,
        ``n' = -e_r psidot``); elbow j moves at ``l2 t_j thetadot_j`` in the plane and with it.
        """
        x = as_points("x", x, 6).reshape(-1, 6)
        cfg = self._config(x)
        geo, p = self._geo, self.params
        xs, _ = finite_rows(x, self.home_pose())
        left = columns(per_block(left_jacobian, xs[:, 3:6]))                           # (3, 3, N)
        n_pts = len(x)
        dpos = np.zeros((3, 6, n_pts))
        dpos[0, 0] = dpos[1, 1] = dpos[2, 2] = 1.0
        omega = np.concatenate([np.zeros((3, 3, n_pts)), left], axis=1)                # (3, 6, N)
        arm, tips = columns(cfg.arm), columns(cfg.tips)                                # (3 legs, 3, N)
        er_all, n_all, w = columns(cfg.er), columns(cfg.n), columns(cfg.w)
        distal, tangent = columns(cfg.distal), columns(cfg.tangent)
        elbows_2d = columns(self._planar.elbows(cfg.theta))                            # (3, 2, 2, N)
        shoulders_2d = np.array([[-0.5 * p.shoulder_separation, 0.0], [0.5 * p.shoulder_separation, 0.0]])
        still = np.zeros((3, 6, n_pts))
        parts, rates = [], [None] * 9
        for k in range(3):
            et = np.broadcast_to(geo.e_t[k][:, None], (3, n_pts))
            er, nrm, tip = er_all[k], n_all[k], tips[k]
            base = geo.base[k][:, None]
            dtip = dpos + cross3(omega, arm[k][:, None])                               # (3, 6, N)
            dpsi = dot3(nrm[:, None], dtip) / w[k]
            der = nrm[:, None] * dpsi
            rates[6 + k] = dpsi
            waist = (np.stack([et, er, nrm], axis=1), et[:, None] * dpsi, still)          # turns about e_t
            shoulders = [base + s[0] * et + s[1] * er for s in shoulders_2d]
            dshoulders = [s[1] * der for s in shoulders_2d]
            elbows, delbows = [], []
            for j in range(2):
                d3 = distal[k, j, 0] * et + distal[k, j, 1] * er
                dtheta = dot3(d3[:, None], dtip) / (p.upper_arm * (distal[k, j, 0] * tangent[k, j, 0]
                                                                   + distal[k, j, 1] * tangent[k, j, 1]))
                rates[2 * k + j] = dtheta
                eu, ew = elbows_2d[k, j]
                elbows.append(base + eu * et + ew * er)
                delbows.append(p.upper_arm * (tangent[k, j, 0] * et + tangent[k, j, 1] * er)[:, None] * dtheta
                               + ew * der)
            backs = [-(p.counterweight_offset / p.upper_arm) * (de - ds) + ds for ds, de in zip(dshoulders, delbows)]
            # The unit's plane turns with its waist: each link at that rate plus its in-plane one.
            upper = [plane_link_part(a, b, nrm, da, db, waist[1])
                     for a, b, da, db in zip(shoulders, elbows, dshoulders, delbows)]
            fore = [plane_link_part(e, tip, nrm, de, dtip, waist[1]) for e, de in zip(elbows, delbows)]
            moved = [(waist[0], waist[1], d) for d in (*delbows, *backs, dtip)]
            parts += [waist, *upper, *fore, *moved]
        rot = columns(cfg.rot)
        parts.append((rot, omega, dpos))
        jv, jw, rots = stack_bodies(parts, body_arrays(self.bodies())[1])
        if not np.all(cfg.ok):
            # Body by body: np.where on the lists would first copy them into one (31, 3, d, N) array.
            jv, jw, rots = ([np.where(cfg.ok, a, np.nan) for a in arrays] for arrays in (jv, jw, rots))
        return jv, jw, rots, np.stack([rates[i] for i in self.actuated])

    def waist_axes(self) -> tuple[FloatArray, FloatArray]:
        """Each leg's waist axis ``e_t`` and waist centre ``B_k`` (row k = leg k), (3, 3) each, m.

        Returns
        -------
        e_t, base : ndarray, shape (3, 3)

        Examples
        --------
        >>> e_t, base = InouePlatform().waist_axes()
        >>> e_t.shape, base.shape
        ((3, 3), (3, 3))
        """
        return self._geo.e_t.copy(), self._geo.base.copy()

    def kinetic_configuration(self, x: ArrayLike) -> dict[str, FloatArray]:
        """What ``body_velocities`` reads of the IK at poses ``x`` (N, 6), batch-first, for a compiled kinetic form.

        Returns
        -------
        dict of str to ndarray
            ``ok`` (N,): reached; ``rot`` (N, 3, 3); per leg ``arm`` (``R a_k``), ``tips``, ``er``,
            ``n`` (N, 3, 3) and ``w`` (N, 3); per leg and shoulder, in the plane, ``distal``,
            ``tangent`` and ``elbows`` (N, 3, 2, 2).
        """
        cfg = self._config(as_points("x", x, 6).reshape(-1, 6))
        return {"ok": cfg.ok, "rot": cfg.rot, "arm": cfg.arm, "tips": cfg.tips, "er": cfg.er, "n": cfg.n,
                "w": cfg.w, "distal": cfg.distal, "tangent": cfg.tangent, "elbows": self._planar.elbows(cfg.theta)}

    # -- configuration ---------------------------------------------------------------------
    @property
    def actuated(self) -> tuple[int, ...]:
        """Indices into ``ALL_JOINTS`` of the actuated joints.

        Returns
        -------
        tuple of int, length ``n``

        Examples
        --------
        >>> InouePlatform().actuated
        (0, 1, 2, 3, 4, 5)
        """
        return tuple(range(9 if self.params.waist_actuators == "active" else 6))

    @property
    def n_joints(self) -> int:
        """``n``: 6 shoulders, plus 3 waists when they are actuated."""
        return len(self.actuated)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the actuated joints, a selection of ``ALL_JOINTS``."""
        return ALL_JOINTS[:self.n_joints]

    @property
    def characteristic_length(self) -> float:
        """Moment arm (m) for comparing moments with forces: the larger platform radius ``max(l6, l7)``.

        A leg force ``F`` at an attachment produces a moment of order ``F`` times that
        attachment's distance from the platform origin (``metrics.wrenches``: the condition
        number's task scaling).
        """
        return max(self.params.platform_apex_radius, self.params.platform_pair_radius)

    def actuator_scales(self) -> tuple[float, float]:
        """Paper 001's ``(Q1, Q2)`` (eq. 18): joint-side torque limits of q3 (= q6) and q4 (= q5) over q1's.

        Returns
        -------
        tuple of float
            Dimensionless.

        Raises
        ------
        ValueError
            If the pairs of eq. 18 differ (q3 != q6 or q4 != q5) or q2 != q1: the scales are undefined.

        Examples
        --------
        >>> [round(s, 12) for s in InouePlatform().actuator_scales()]
        [0.75, 0.75]
        """
        t = joint_side(self.params.motor_torques, self.params.gear_ratios)      # every joint, active or not
        for a, b in ((0, 1), (2, 5), (3, 4)):
            if not np.isclose(t[a], t[b], rtol=1e-12, atol=0.0):
                raise ValueError(f"actuator scales need equal torque limits on {ALL_JOINTS[a]} and "
                                 f"{ALL_JOINTS[b]} (paper 001 eq. 18), got {t[a]:g} and {t[b]:g} N m")
        return float(t[2] / t[0]), float(t[3] / t[0])

    def base_joints(self) -> FloatArray:
        """Waist centres ``B_k`` (the midpoints of each leg's shoulders), (3, 3), m.

        Returns
        -------
        ndarray, shape (3, 3)
            Row k is leg k's, m.
        """
        return self._geo.base.copy()

    def platform_joints(self) -> FloatArray:
        """U-joint centres ``p_k`` in the platform frame (origin at the task point), (3, 3), m.

        Returns
        -------
        ndarray, shape (3, 3)
            Row k is attachment k's, m.
        """
        return self._geo.attach.copy()

    def size(self) -> float:
        """Device size ``S`` (m): bounds every vector in a tip: ``max |B_k| + l1/2 + l2 + l3 + max |p_k|``.

        Returns
        -------
        float
            m.
        """
        p = self.params
        return (max(p.base_apex_radius, p.base_pair_radius) + 0.5 * p.shoulder_separation + p.upper_arm
                + p.forearm + self.characteristic_length)

    def home_pose(self, distance: float = 0.25) -> FloatArray:
        """The platform origin at ``(0, 0, distance)``, zero orientation, (6,).

        Parameters
        ----------
        distance : float
            Height of the platform origin, m (paper 001's workspace centre: 25 cm).

        Returns
        -------
        ndarray, shape (6,)
            m and rad.

        Examples
        --------
        >>> InouePlatform().home_pose().tolist()
        [0.0, 0.0, 0.25, 0.0, 0.0, 0.0]
        """
        return np.array([0.0, 0.0, float(distance), 0.0, 0.0, 0.0])

    # -- pieces -----------------------------------------------------------------------------
    def _plane(self, psi: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``e_r(psi)`` and ``n`` of each leg, (..., 3, 3), for waist angles (..., 3)."""
        c, s = np.cos(psi)[..., None], np.sin(psi)[..., None]
        e_rad = self._geo.e_rad
        return c * _EZ + s * e_rad, c * e_rad - s * _EZ

    def _legs(self, tips: FloatArray) -> tuple:
        """Waist (front branch) and five-bar (elbows outward) of tips (..., 3, 3)."""
        g = self._geo
        d = tips - g.base
        u = row_dot(d, g.e_t)
        up, out = d[..., 2], row_dot(d, g.e_rad)
        w = np.hypot(up, out)
        psi = np.arctan2(out, up)
        er, n = self._plane(psi)
        point = np.stack([u, w], -1)
        theta, ok = self._planar.inverse(point, "+-")                 # (..., 3, 2)
        return psi, w, er, n, theta, self._in_plane(point, theta), np.all(ok, -1)

    def _in_plane(self, point: FloatArray, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        elbows = self._planar.elbows(theta)                          # (..., 3, 2, 2)
        return point[..., None, :] - elbows, np.stack([-np.sin(theta), np.cos(theta)], -1)

    def _config(self, x: FloatArray) -> _Config:
        """IK of the whole device at poses ``x`` (..., 6); non-finite poses are not ``ok``.

        The last batch's is kept (``_LAST_CONFIG``): a map asks for the limits, ``jacobian``,
        ``force_map``, ``singularity`` and the mass matrix at the same poses. Read-only.
        """
        x = np.asarray(x, dtype=float)
        cfg = _LAST_CONFIG.get(self, x)
        return cfg if cfg is not None else _LAST_CONFIG.put(self, x, self._build_config(x))

    def _build_config(self, x: FloatArray) -> _Config:
        x, finite = finite_rows(x, self.home_pose())
        rot, arm = per_block(self._turned, x[..., 3:6])          # once per orientation of a repeating block
        tips = x[..., None, :3] + arm
        psi, w, er, n, theta, (distal, tangent), ok = self._legs(tips)
        return _Config(rot, arm, tips, psi, w, er, n, theta, distal, tangent, ok & finite)

    def _turned(self, rotvec: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Rotations (..., 3, 3) of rotation vectors (..., 3) and the attachments they turn, ``R a_k`` (..., 3, 3)."""
        rot = rotation_matrix(rotvec)
        return rot, np.einsum("...ij,kj->...ki", rot, self._geo.attach)

    def _joints(self, cfg: _Config, which=range(9)) -> FloatArray:
        """Joints ``which`` of all nine (..., len(which)), wrapped into their limits where possible; ``nan`` where
        unreachable."""
        raw = np.concatenate([cfg.theta.reshape(cfg.theta.shape[:-2] + (6,)), cfg.psi], -1)
        lo, hi = self.params.lower_limits, self.params.upper_limits
        out = np.stack([wrap_into(raw[..., i], lo[i], hi[i])[0] for i in which], -1)
        return np.where(cfg.ok[..., None], out, np.nan)

    def _pose(self, q: ArrayLike, x: ArrayLike | None) -> FloatArray:
        if x is None:
            x, _ = self.forward(q)
        return as_points("x", x, 6)

    # -- kinematics -------------------------------------------------------------------------
    def all_joints(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """All nine joints ``q1..q6, w1..w3`` (..., 9) at poses ``x`` (..., 6), passive waists included.

        Parameters
        ----------
        x : array_like, shape (..., 6)
            Poses, m and rad.

        Returns
        -------
        q : ndarray, shape (..., 9)
            rad; ``nan`` where unreachable.
        reachable : ndarray of bool, shape (...)
        """
        cfg = self._config(as_points("x", x, 6))
        return self._joints(cfg), cfg.ok

    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Actuated joints ``q`` (..., n) reaching poses ``x`` (..., 6), and ``reachable`` (...).

        Closed form, branch as in the module doc. Angles are shifted by multiples of 2 pi into
        their limits where they fit (limits are checked by ``feasible``).

        Examples
        --------
        >>> mech = InouePlatform()
        >>> q, ok = mech.inverse(mech.home_pose())
        >>> q.shape, bool(ok)
        ((6,), True)
        """
        cfg = self._config(as_points("x", x, 6))
        return self._joints(cfg, range(self.n_joints)), cfg.ok

    def forward(self, q: ArrayLike, guess: ArrayLike | None = None, *, rtol: float = FK_RTOL,
                max_iter: int = 50) -> tuple[FloatArray, BoolArray]:
        """Pose ``x`` (..., 6) of actuated joints ``q`` (..., n), and whether it assembles (...).

        Each five-bar's tip in its plane, ``(u, w)``, is closed form (assembly "up"). Passive
        waists: Newton on the pose (``_newton``: the residual is every tip's ``(u, w)``, each
        step's turn limited to ``MAX_TURN``) from ``guess`` (default ``home_pose()``) until the
        residuals are within ``rtol * size()`` (``FK_RTOL``: derivation there); where that fails
        or lands on another assembly, continuation from home along the straight joint path
        (``CONTINUATION_STEPS`` Newton solves). Active waists: the tips are closed form and
        must be the platform's distances apart within ``rtol * size()``; the pose follows from
        the three tips. ``ok`` also requires that IK of the pose gives ``q`` back within
        ``BRANCH_TOL`` and that every U-joint bends below 90 deg (a U-joint cannot pass it; the
        platform's twin flipped about its long axis is such an assembly): joints a pose does not
        reproduce are reported as not assembling, never with a wrong pose. FK is not unique: at
        extreme poses (beyond ~30 deg tilt) an assembly other than the given pose can pass
        these checks.

        Examples
        --------
        >>> mech = InouePlatform()
        >>> q, _ = mech.inverse(mech.home_pose())
        >>> x, ok = mech.forward(q)
        >>> bool(np.allclose(x, mech.home_pose(), rtol=0.0, atol=1e-12)), bool(ok)
        (True, True)
        """
        q, finite = finite_rows(as_points("q", q, self.n_joints), self.inverse(self.home_pose())[0])
        shoulders = q[..., :6].reshape(q.shape[:-1] + (3, 2))
        with np.errstate(invalid="ignore"):
            point, ok = self._planar.forward(shoulders, "up")              # (..., 3, 2)
        ok = np.all(ok, -1) & finite
        tol = rtol * self.size()
        if self.n_joints == 9:
            tips = self._tips(point, q[..., 6:9])
            attach = self._geo.attach
            pairs = ((0, 1), (1, 2), (2, 0))
            with np.errstate(invalid="ignore"):
                span = [np.linalg.norm(tips[..., i, :] - tips[..., j, :], axis=-1) for i, j in pairs]
                for (i, j), d in zip(pairs, span):
                    ok &= np.abs(d - np.linalg.norm(attach[i] - attach[j])) <= tol
            x = self._pose_of_tips(np.where(ok[..., None, None], tips, self._config(self.home_pose()).tips))
        else:
            start = self.home_pose() if guess is None else as_points("guess", guess, 6)
            x = np.array(np.broadcast_to(start, point.shape[:-2] + (6,)))
            x, done = self._newton(np.where(ok[..., None, None], point, 0.0), x, tol, max_iter)
            done = np.array(done & self._assembles(q, x))
            retry = ok & ~done
            if retry.any():                                  # continuation from home along the joint path
                x[retry], done[retry] = self._continuation(q[retry], tol, max_iter)
            ok &= done
        ok &= self._assembles(q, np.where(ok[..., None], x, self.home_pose()))
        return np.where(ok[..., None], x, np.nan), ok

    def _assembles(self, q: FloatArray, x: FloatArray) -> BoolArray:
        """IK of ``x`` (..., 6) gives ``q`` (..., n) back within ``BRANCH_TOL`` and every U-joint bends below 90 deg."""
        cfg = self._config(x)
        back = self._joints(cfg)[..., :self.n_joints]
        with np.errstate(invalid="ignore"):
            same = np.all(np.abs(np.angle(np.exp(1j * (back - q)))) <= BRANCH_TOL, -1)
            return cfg.ok & same & np.all(self._bends(cfg) < np.pi / 2, -1)

    def _continuation(self, q: FloatArray, tol: float, max_iter: int, steps: int = CONTINUATION_STEPS):
        """FK of passive-waist joints ``q`` (k, 6) by Newton along the straight joint path from home."""
        home = self.home_pose()
        q0 = self.inverse(home)[0]
        dq = np.angle(np.exp(1j * (q - q0)))
        x = np.array(np.broadcast_to(home, q.shape[:-1] + (6,)))
        done = np.ones(q.shape[:-1], bool)
        for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
            with np.errstate(invalid="ignore"):
                point, ok = self._planar.forward((q0 + s * dq).reshape(q.shape[:-1] + (3, 2)), "up")
            done &= np.all(ok, -1)
            x, conv = self._newton(np.where(done[..., None, None], point, 0.0), x, tol, max_iter)
            done &= conv
        return x, done & self._assembles(q, x)

    def _tips(self, point: FloatArray, psi: FloatArray) -> FloatArray:
        er, _ = self._plane(psi)
        return self._geo.base + point[..., 0:1] * self._geo.e_t + point[..., 1:2] * er

    def _newton(self, point, x, tol, max_iter):
        """Newton steps on the pose until each tip's in-plane coordinates ``(u, w)`` are ``point`` (..., 3, 2).

        ``u = d . e_t`` and ``w = |d x e_t|`` (``d = o + R p_k - B_k``) are defined for every pose,
        and the waists are free, so the residual is ``(u, w) - point``; its rates per twist
        are the rows ``[e_t, a_k x e_t]`` and ``[e_r, a_k x e_r]``. Orientation is a proper
        rotation throughout, so a mirror image of the platform is never reached.
        """
        g = self._geo
        centre, rot = x[..., :3].copy(), rotation_matrix(x[..., 3:6])
        done = np.zeros(x.shape[:-1], bool)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(max_iter):
                arm = np.einsum("...ij,kj->...ki", rot, g.attach)
                d = centre[..., None, :] + arm - g.base
                up, out = d[..., 2], np.sum(d * g.e_rad, -1)
                w = np.hypot(up, out)
                residual = np.stack([np.sum(d * g.e_t, -1), w], -1) - point          # (..., 3, 2)
                residual = residual.reshape(residual.shape[:-2] + (6,))
                done = np.all(np.abs(residual) <= tol, -1)
                if done.all():
                    break
                er = (up[..., None] * _EZ + out[..., None] * g.e_rad) / w[..., None]
                dirs = np.stack([np.broadcast_to(g.e_t, er.shape), er], -2)              # (..., 3, 2, 3)
                dirs = dirs.reshape(dirs.shape[:-3] + (6, 3))
                rows = np.concatenate([dirs, np.cross(np.repeat(arm, 2, axis=-2), dirs)], -1)
                inv, good = batched_inverse(rows)
                step = -np.einsum("...ij,...j->...i", np.where(good[..., None, None], inv, 0.0), residual)
                step = np.where((done | ~good)[..., None] | ~np.isfinite(step), 0.0, step)
                # A full step may turn the platform by up to pi about its long axis (a slim
                # platform's tips barely move, and its flipped twin is close in tip space):
                # limit each step's turn to MAX_TURN, so Newton stays on the branch of the guess.
                turn = np.linalg.norm(step[..., 3:], axis=-1, keepdims=True)
                step = step * np.minimum(1.0, MAX_TURN / np.maximum(turn, MAX_TURN))
                centre = centre + step[..., :3]
                rot = rotation_matrix(step[..., 3:]) @ rot
        return np.concatenate([centre, rotation_vector(rot)], -1), done

    def _pose_of_tips(self, tips: FloatArray) -> FloatArray:
        """Pose (..., 6) that puts the attachments on the tips (..., 3, 3): frames of the two triangles."""
        def frame(pts):
            e1 = pts[..., 1, :] - pts[..., 0, :]
            e1 = e1 / np.linalg.norm(e1, axis=-1, keepdims=True)
            e3 = np.cross(e1, pts[..., 2, :] - pts[..., 0, :])
            e3 = e3 / np.linalg.norm(e3, axis=-1, keepdims=True)
            return np.stack([e1, np.cross(e3, e1), e3], -1)

        attach = self._geo.attach
        rot = frame(tips) @ frame(attach).T
        origin = tips.mean(-2) - np.einsum("...ij,j->...i", rot, attach.mean(0))
        return np.concatenate([origin, rotation_vector(rot)], -1)

    # -- velocities and statics -------------------------------------------------------------
    def coordinate_rates_to_twist(self, x: ArrayLike) -> FloatArray:
        """``T = blockdiag(I, J_l(r))`` (..., 6, 6), ``xi = T xdot`` (``rotations.pose_rates_to_twist``)."""
        return pose_rates_to_twist(as_points("x", x, 6))

    def inverse_jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``K`` (..., n, 6) with ``qdot = K [v; omega]``: shoulder rows ``[g, a_k x g]``, waist rows.

        ``x`` is the pose of ``q`` (computed by ``forward`` when not given). Entries are
        ``inf``/``nan`` at an inverse singularity (a five-bar leg stretched or folded; for a waist
        row, the tip on its waist axis).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints, rad.
        x : array_like, shape (..., 6), optional
            The pose of ``q``.

        Returns
        -------
        ndarray, shape (..., n, 6)
            rad/m on the ``v`` columns, dimensionless on the ``omega`` columns.
        """
        rows, denom = self._inverse_jacobian_parts(q, x)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return rows / denom[..., None]

    def _inverse_jacobian_parts(self, q: ArrayLike, x: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        """``K = diag(1 / d) R``: rows ``R`` (..., n, 6), finite at every reachable pose, and ``d`` (..., n).

        ``d`` is ``a1 (distal . tangent)`` for a shoulder and the tip's distance from the axis
        for a waist: it is 0 exactly where that actuator is at an inverse singularity, so
        ``J = K^-1 = R^-1 diag(d)`` has that column 0 without dividing by 0. ``nan`` where
        unreachable.
        """
        cfg = self._config(self._pose(q, x))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            denom = self.params.upper_arm * np.sum(cfg.distal * cfg.tangent, -1)             # (..., 3, 2)
            d3 = (cfg.distal[..., 0:1] * self._geo.e_t[:, None, :]
                  + cfg.distal[..., 1:2] * cfg.er[..., None, :])                           # (..., 3, 2, 3)
            d3 = d3.reshape(d3.shape[:-3] + (6, 3))
            denom = denom.reshape(denom.shape[:-2] + (6,))
            if self.n_joints == 9:
                d3 = np.concatenate([d3, cfg.n], -2)
                denom = np.concatenate([denom, cfg.w], -1)
                arm = np.concatenate([np.repeat(cfg.arm, 2, axis=-2), cfg.arm], -2)
            else:
                arm = np.repeat(cfg.arm, 2, axis=-2)
            rows = np.concatenate([d3, np.cross(arm, d3)], -1)
        ok = cfg.ok[..., None]
        return np.where(ok[..., None], rows, np.nan), np.where(ok, denom, np.nan)

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = K^T`` (..., 6, n): the wrench ``w = [f; m] = A tau`` held by joint torques ``tau``."""
        return np.swapaxes(self.inverse_jacobian(q, x), -1, -2)

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., 6, n) with ``[v; omega] = J qdot``; ``tau = J^T w``. ``inf`` where ``K`` is singular.

        Passive waists: ``K^-1``. Active (redundant) waists: ``K^+ = (K^T K)^-1 K^T``, exact for
        consistent joint rates; ``tau = J^T w`` is then the least-norm torque with ``A tau = w``.

        Examples
        --------
        >>> mech = InouePlatform()
        >>> x = mech.home_pose()
        >>> q, _ = mech.inverse(x)
        >>> mech.jacobian(q, x).shape
        (6, 6)
        """
        x = self._pose(q, x)
        code = self.singularity(q, x)
        legs = self.singular_legs(q, x) & (code == 1)[..., None]
        if self.n_joints == 6:
            # K^-1 = R^-1 diag(d): no inf row of K to invert where a leg is stretched or folded.
            rows, denom = self._inverse_jacobian_parts(q, x)
            jac = batched_inverse(rows)[0] * denom[..., None, :]
        else:
            k = self.inverse_jacobian(q, x)
            kt = np.swapaxes(k, -1, -2)
            with np.errstate(invalid="ignore", over="ignore"):
                jac = batched_inverse(kt @ k)[0] @ kt
        # Where the pose is classed singular J is exact (``base.singular_limit``): a singular
        # actuator's column is 0, not rounding noise of 1e-17 read downstream as 1e16 N.
        return singular_limit(jac, legs, code == 2)

    # -- singularities ----------------------------------------------------------------------
    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Actuators at an inverse singularity, bool (..., n).

        A shoulder: its distal link along its upper arm, ``|d . t| <= tol l2 l3`` (stretched or
        folded leg), with ``tol`` the five-bar's ``FiveBar.singular_tolerance`` (derived there
        from eps and the link lengths: the ``|sin|`` rounding alone gives at an exactly singular
        pose, ~1e-7). A waist (active): the tip on its axis, ``w <= tol (l2 + l3)``.
        """
        cfg = self._config(self._pose(q, x))
        p = self.params
        tol = self._planar.singular_tolerance
        with np.errstate(invalid="ignore"):
            legs = np.abs(np.sum(cfg.distal * cfg.tangent, -1)) <= tol * p.upper_arm * p.forearm
            legs = legs.reshape(legs.shape[:-2] + (6,))
            if self.n_joints == 9:
                legs = np.concatenate([legs, cfg.w <= tol * (p.upper_arm + p.forearm)], -1)
        return legs & cfg.ok[..., None]

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """0 none, 1 inverse (``singular_legs``), 2 direct (the task-scaled ``K`` near rank-deficient), int8 (...).

        Direct: ``sigma_min <= tol sigma_max`` of ``K diag(1, 1, 1, 1/L, 1/L, 1/L)`` (``L`` the
        ``characteristic_length``, so every entry is in rad/m; ``tol`` as in ``singular_legs``,
        the five-bar's rule for its own direct class): the platform can move with the actuators
        locked (e.g. the passive waists' singularity).
        """
        x = self._pose(q, x)
        # ``jacobian``, the map's ``singularity`` node and the mass matrix each ask at the same poses.
        code = _LAST_SINGULARITY.get(self, x)
        if code is None:
            code = _LAST_SINGULARITY.put(self, x, self._singularity(q, x))
        return code.copy()

    def _singularity(self, q: ArrayLike, x: FloatArray) -> NDArray[np.int8]:
        k = self.inverse_jacobian(q, x)
        scale = np.array([1.0, 1.0, 1.0] + [1.0 / self.characteristic_length] * 3)
        finite = np.all(np.isfinite(k), axis=(-2, -1))
        sv = np.linalg.svd(np.where(finite[..., None, None], k * scale, 1.0), compute_uv=False)
        direct = finite & (sv[..., -1] <= self._planar.singular_tolerance * sv[..., 0])
        inverse = np.any(self.singular_legs(q, x), -1)
        return np.where(inverse, 1, np.where(direct, 2, 0)).astype(np.int8)

    # -- limits -----------------------------------------------------------------------------
    def bend_angles(self, x: ArrayLike) -> FloatArray:
        """U-joint bend of each leg (..., 3), rad: ``angle(n_k, R e_rad(phi_k))``, 0 upright at home.

        Parameters
        ----------
        x : array_like, shape (..., 6)
            Poses, m and rad.

        Returns
        -------
        ndarray, shape (..., 3)
            rad; ``nan`` where unreachable.
        """
        cfg = self._config(as_points("x", x, 6))
        return np.where(cfg.ok[..., None], self._bends(cfg), np.nan)

    def _bends(self, cfg: _Config) -> FloatArray:
        shafts = np.einsum("...ij,kj->...ki", cfg.rot, self._geo.e_rad)
        return row_angle(cfg.n, shafts)

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Reach, limits of all nine joints (passive waists too) and U-joint bends, shape (...).

        ``x`` (the pose of ``q``) is computed by ``forward`` when not given; the passive
        waists' angles come from it.
        """
        q = as_points("q", q, self.n_joints)
        cfg = self._config(self._pose(q, x))
        # The actuated joints are the given q; only the passive waists come from the pose.
        full = np.empty(cfg.ok.shape + (9,))
        full[..., :self.n_joints] = q
        if self.n_joints < 9:
            full[..., self.n_joints:] = self._joints(cfg, range(self.n_joints, 9))
        p = self.params
        with np.errstate(invalid="ignore"):
            ok = cfg.ok & np.all(np.isfinite(q), axis=-1)
            ok &= np.all((full >= np.asarray(p.lower_limits)) & (full <= np.asarray(p.upper_limits)), -1)
            ok &= np.all(self._bends(cfg) <= p.ujoint_limit, -1)
        return ok

    # -- drawing ----------------------------------------------------------------------------
    def link_points(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """One polyline through every link, (..., 22, 3), m (the platform triangle is closed).

        Per leg: first shoulder, its elbow, tip, second elbow, second shoulder, waist centre
        (six points, three legs); then tips 1, 2, 3, 1 (the platform). ``x`` is the pose of
        ``q`` (computed by ``forward`` when not given).
        """
        cfg = self._config(self._pose(q, x))
        g = self._geo
        half = 0.5 * self.params.shoulder_separation
        shoulders = g.base[:, None, :] + np.array([-half, half])[:, None] * g.e_t[:, None, :]    # (3, 2, 3)
        shoulders = np.broadcast_to(shoulders, cfg.tips.shape[:-1] + (2, 3))
        elbows = self._planar.elbows(cfg.theta)                                                 # (..., 3, 2, 2)
        elbow3 = (g.base[:, None, :] + elbows[..., 0:1] * g.e_t[:, None, :]
                  + elbows[..., 1:2] * cfg.er[..., None, :])                                     # (..., 3, 2, 3)
        seq = []
        for k in range(3):
            seq += [shoulders[..., k, 0, :], elbow3[..., k, 0, :], cfg.tips[..., k, :], elbow3[..., k, 1, :],
                    shoulders[..., k, 1, :], np.broadcast_to(g.base[k], cfg.tips[..., k, :].shape)]
        seq += [cfg.tips[..., 0, :], cfg.tips[..., 1, :], cfg.tips[..., 2, :], cfg.tips[..., 0, :]]
        return np.where(cfg.ok[..., None, None], np.stack(seq, -2), np.nan)
