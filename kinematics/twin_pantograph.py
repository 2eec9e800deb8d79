"""Twin-Pantograph haptic pen (Stocco, Salcudean, Sassani, paper 001, sec. V-VI).

One module over the ~600-line guide on purpose: the reconstructed geometry, its inverse
kinematics, the 6-DOF and 5-DOF Jacobians, the feasibility tests and the body frames all read
the same list of reconstruction choices below, which a reader checks against the paper in one place.

Two 3-DOF positioners ("units") hold the two ends of a pen through universal joints. Each
unit is a waist joint plus a planar five-bar (pantograph) in the plane the waist turns, like
the Inverse3's positioner. Paper 001's figures are not in our text, so the geometry below is
a reconstruction from what the text says; every choice is a parameter or is listed here.

Frame and geometry (our reconstruction)
---------------------------------------
* Base frame = the paper's ``(i, j, k)`` as ``(x, y, z)``; the base origin ``o_b`` is 0. The
  workspace lies along ``+z`` (the paper's "distance measured along the k axis", 25 cm).
* At zero orientation the pen lies along ``+y`` (the paper's ``j``: Table I's smallest
  moment, 0.5 cm, is the twist about the pen, and its 5-DOF velocity scaling drops
  ``omega_j``). The pen's reference point (the task point) is, by default, the midpoint of its
  two U-joint centres; ``ujoint_lever``, ``reference_along`` and ``reference_offset`` move the
  U-joints and the task point for the other readings of the paper (issue 23 sec. 1,
  ``scripts/reference_point.py``, ``docs/reproduction.md``).
* Unit A (actuators ``q1`` waist, ``q2``, ``q3`` shoulders) sits at ``y = -l4/2``, unit B
  (``q4`` waist, ``q5``, ``q6``) at ``y = +l4/2``; ``l4`` is the paper's "base length"
  (8 cm in Table VII; it sets the device's extent along the pen and "the height"). Unit A
  holds the pen end at ``-l6/2`` along the pen, unit B the end at ``+l6/2`` (``-+ ujoint_lever
  l6`` in general).
* A unit's waist axis is parallel to ``x`` through ``(0, y_k, 0)``; the waist angle ``psi``
  turns the five-bar plane about it. The plane is spanned by ``e_x`` and the radial
  direction ``e_r(psi) = (0, -sin psi, cos psi)``; its normal ``n = e_x x e_r``. So at home
  both planes are nearly perpendicular to the pen, and the paper's passive-waist singularity
  ("the platform axis lies in the plane of the five-bar") is far from the workspace.
* The two shoulder joints lie on the waist axis at ``x = -l1/2`` (``q2``/``q5``) and
  ``x = +l1/2`` (``q3``/``q6``); ``l1`` is the shoulder separation ("width of the shoulder
  actuators", Table VII's minimum 2.4 cm). Upper arms (proximal links) ``l2``, forearms
  (distal links) ``l3``, as in Tables III/VII. A shoulder angle is measured in the plane from
  ``+e_x`` towards ``+e_r`` (about ``+n``), the five-bar convention of ``kinematics.fivebar``.
* IK branch: waist "front" (the tip is at ``+e_r``, radial distance ``w > 0``), elbows
  outward (``q2`` elbow towards ``-x``, ``q3`` elbow towards ``+x``); FK assembly: tip beyond
  the elbows (``FiveBar`` modes ``"+-"`` and ``"up"``).
* U-joints: the shaft on the unit side is the plane normal (fixed in a forearm), the shaft on
  the pen side is the pen. The bend angle is the angle between them, ``angle(p, -n_k)``
  (0 at home), limited to ``ujoint_limit`` (paper: +-85 deg). At 90 deg the U-joint and the
  roll drive form a singular spherical wrist (paper sec. V, singularity (iv)).
* Roll (6-DOF version, ``q7``): a drive on unit A's ``q2`` forearm turns the U-joint's input
  yoke about ``n_A``; the cross axis ``a1`` (in the yoke) and ``a2 = R e_x`` (in the pen)
  carry the roll to the pen: ``a1 = unit(n_A x a2)``, ``q7`` = angle about ``n_A`` from the
  forearm direction to ``a1``. Unit B's end rolls freely.
* Not used: the paper's ``l5`` (not a design variable in its tables); link widths, joint
  offsets and collisions.

Actuation (parameters ``redundant_waist`` and ``roll_actuator``)
----------------------------------------------------------------
``q4`` (unit B's waist) is the paper's redundant actuator; ``q7`` the roll.

==================  =============  ======  ============================================
redundant_waist     roll_actuator  task    actuators -> force map
==================  =============  ======  ============================================
"active" (default)  "passive"      5-DOF   q1..q6: 5 x 6, redundant (paper Table VII)
"passive"           "active"       6-DOF   q1-q3, q5-q7: 6 x 6 (paper Table III)
"passive"           "passive"      5-DOF   q1-q3, q5, q6: 5 x 5
"active"            "active"       6-DOF   q1..q7: 6 x 7, redundant
==================  =============  ======  ============================================

The passive joints (q4 when passive, the U-joints, the free roll) follow from the pose; a
passive q4 is still checked against its limits, the U-joints against ``ujoint_limit``.
Paper 001 gives no joint ranges: the defaults are wide (waists +-90 deg, shoulders over
270 deg) and only the U-joint bend is the paper's.
Because the geometry is reconstructed, GII values computed with this model are not expected
to reproduce the paper's (0.327 for Table III, 0.234 for Table VII); trends can be compared.

Task coordinates and velocities
-------------------------------
6-DOF: ``x = (x, y, z, rx, ry, rz)``, the pen centre (m) and the rotation vector of the pen
frame ``R`` (rad, base frame; pen axis ``R e_y``). 5-DOF: ``x = (x, y, z, rx, rz)``, the pen
centre and the *tilt* ``R = exp([rx, 0, rz]x)`` (no roll): ``|(rx, rz)|`` is paper 001's tip
angle ``theta_1``.

Jacobians use twists, not coordinate rates. 6-DOF: ``xi = [v; omega]`` with ``v`` the pen
centre's velocity and ``omega`` the pen's angular velocity, both in the base frame.
5-DOF: ``xi = [v; omega . a; omega . b]`` with ``a = R e_x``, ``b = R e_z`` the pen frame's
axes across the pen (at zero tilt: ``omega_x``, ``omega_z``, the paper's ``omega_i, omega_k``);
the roll rate is not a task velocity. ``coordinate_rates_to_twist(x)`` converts.

* ``inverse_jacobian``: ``K`` (..., n, m), ``qdot = K xi``, closed form at every pose.
* ``force_map``: ``A = K^T`` (..., m, n), ``w = A tau``: the wrench the actuator torques
  ``tau`` hold, ``w = [f; m]`` (6-DOF; force and moment about the pen centre, base frame)
  or ``[f; m . a; m . b]`` (5-DOF). Virtual work: ``tau . qdot = w . xi`` for every motion.
  With redundant actuation the force set is the zonotope ``A [-t, t]^n``
  (``metrics.zonotopes.zonotope(A, torque_limits=...)``).
* ``jacobian``: ``J`` (..., m, n) with ``xi = J qdot`` for every *consistent* ``qdot``:
  ``K^-1`` when square, ``K^+ = (K^T K)^-1 K^T`` when redundant. Statics ``tau = J^T w``
  (square: the unique torques; redundant: the least-norm torques with ``A tau = w``).

Over 600 lines for a stated reason: one model class whose IK, Jacobian rows and limits share
the private ``_Unit`` / ``_Config`` structures, and almost half the file is docstrings (this
reconstruction's description and the numpydoc sections of issue 8).
"""
from __future__ import annotations

import functools
import threading
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import pose_memo
from .actuated import ActuatedSubset
from .angles import wrap_into
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, memoised
from .bodies import Body, body_arrays, columns, cross3, plane_link_part, point_mass, rod, stack_bodies
from .mass_params import G_CM2, MOMENTS, check_mass_params, link_frames, mass_param_info
from .pose_memo import PoseMemo, fold_rows, per_block
from .rotations import (
    angle_in,
    batched_inverse,
    finite_rows,
    left_jacobian,
    rotation_matrix,
    rotation_vector,
    spd_inverse,
    tilt_matrix,
    tilt_of_direction,
)
from .validation import (
    as_points,
    check_number,
    choice,
    finite_angles,
    optional_positive_vector,
    positive_finite,
    positive_vector,
)

ALL_JOINTS = ("q1", "q2", "q3", "q4", "q5", "q6", "q7")
#: The mass model's parts (``link_masses``, kg), each unit's once and the pen: the waist body
#: (everything turning with a waist joint: the shoulder motors and their bracket), each upper arm
#: and forearm (uniform rods), each elbow joint and the tip joint (point masses: clevises, bearings,
#: pin, U-joint), each shoulder's counterweight (a point ``counterweight_offset`` behind the
#: shoulder on the upper arm's extension), and the pen (a slender rod between the U-joint centres).
LINKS = ("waist", "upper_arm", "forearm", "elbow", "tip", "counterweight", "pen")
#: Radius (m) of the pen rod when its roll is driven (6-DOF): paper 001's pencil-sized grip, 0.63 cm
#: across. With the roll passive (5-DOF) the pen is a line: its free roll carries no energy.
PEN_RADIUS = 0.00315
MODES = ("active", "passive")
_DEG = np.pi / 180.0
_SLACK = 8 * np.finfo(float).eps
#: A redundantly actuated FK is "consistent" if the two tips are l6 apart to this relative tolerance.
CONSISTENCY_TOL = 1e-8
_EX = np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True, slots=True)
class TwinPantographParams:
    """Geometry (m), actuators, limits (rad) and actuation of a Twin-Pantograph.

    Defaults: paper 001 Table VII's optimum for a workspace 25 cm away (l1 = 2.4, l2 = 17,
    l3 = 23, l4 = 8, l6 = 7 cm; waist torque 1.6 x shoulder torque), redundant waist active,
    roll passive: the haptic pen the paper built. Torques are illustrative (the paper gives
    only ratios).
    """

    shoulder_separation: float = 0.024
    upper_arm: float = 0.170
    forearm: float = 0.230
    unit_separation: float = 0.080
    pen_length: float = 0.070
    ujoint_limit: float = 85 * _DEG
    motor_torques: tuple[float, ...] = (0.16, 0.1, 0.1, 0.16, 0.1, 0.1, 0.003)
    gear_ratios: tuple[float, ...] = (1.0,) * 7
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    lower_limits: tuple[float, ...] = (-90 * _DEG, 0.0, -90 * _DEG, -90 * _DEG, 0.0, -90 * _DEG, -180 * _DEG)
    upper_limits: tuple[float, ...] = (90 * _DEG, 270 * _DEG, 180 * _DEG, 90 * _DEG, 270 * _DEG, 180 * _DEG,
                                       180 * _DEG)
    redundant_waist: str = "active"
    roll_actuator: str = "passive"
    #: The reading of the pen's geometry (paper 001 gives no figure of it; issue 23 sec. 1,
    #: ``scripts/reference_point.py``). ``ujoint_lever``: each U-joint's distance from the pen's
    #: centre (their midpoint) as a multiple of ``l6``: 0.5 puts them ``l6`` apart (``l6`` the
    #: U-joint separation), 1.0 puts them ``2 l6`` apart (``l6`` the lever from the centre).
    #: ``reference_along``: where the task point (the handle's reference point, whose position and
    #: forces the task coordinates are) sits along the pen, as a fraction of the centre-to-U-joint
    #: distance: 0 the centre, -1 unit A's U-joint, +1 unit B's. ``reference_offset`` (m): its
    #: offset across the pen along the pen frame's ``b = R e_z`` (at home ``+z``, away from the base).
    #: The defaults are this model's original reading: the midpoint of two U-joints ``l6`` apart.
    ujoint_lever: float = 0.5
    reference_along: float = 0.0
    reference_offset: float = 0.0
    #: One sensor count of each joint (rad): paper 001's prototype senses every active joint
    #: with a 4000 cpt optical encoder on the direct-drive motor: 360 / 4000 = 0.09 deg.
    joint_resolution: tuple[float, ...] = (0.09 * _DEG,) * 7
    #: Mass model (``kinematics.mass_params``), kg, kg m^2 and m, per unit (both units alike): see
    #: ``LINKS`` and ``TwinPantograph.bodies``. ``waist_inertia`` is the waist body's principal moments
    #: about its centre on the waist axis (x: the waist axis, y: the radial direction, z: the plane
    #: normal); rotor inertias motor side, one per joint (the actuated ones are used). The defaults
    #: are the estimates of ``resources/presets/twin_pantograph.toml`` (this design's lengths, the
    #: prototype's parts), off by default: paper 001 gives no masses.
    link_masses: tuple[float, ...] = (0.72, 0.00769, 0.0104, 0.0247, 0.0346, 0.325, 0.0084)
    waist_inertia: tuple[float, float, float] = (17600 * G_CM2, 18600 * G_CM2, 2180 * G_CM2)
    counterweight_offset: float = 0.035
    rotor_inertias: tuple[float, ...] = ((134 * G_CM2,) + (68.1 * G_CM2,) * 2) * 2 + (1 * G_CM2,)
    mass_model: str = "none"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_mass_params(self, LINKS, ALL_JOINTS, moments=("waist_inertia",))
        for name in ("shoulder_separation", "upper_arm", "forearm", "unit_separation", "pen_length",
                     "counterweight_offset"):
            set_(self, name, positive_finite(name, getattr(self, name), "m"))
        set_(self, "ujoint_lever", positive_finite("ujoint_lever", self.ujoint_lever))
        for name, unit in (("reference_along", ""), ("reference_offset", "m")):
            value = getattr(self, name)
            check_number(value, name=name, unit=unit, finite=True)
            set_(self, name, float(value))
        set_(self, "ujoint_limit", angle_in("ujoint_limit", self.ujoint_limit, 0.0, np.pi / 2, open_lower=True))
        set_(self, "motor_torques", positive_vector("motor_torques", self.motor_torques, ALL_JOINTS, "N m"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ALL_JOINTS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ALL_JOINTS, "rad/s"))
        set_(self, "joint_resolution", positive_vector("joint_resolution", self.joint_resolution, ALL_JOINTS, "rad"))
        set_(self, "lower_limits", finite_angles("lower_limits", self.lower_limits, ALL_JOINTS))
        set_(self, "upper_limits", finite_angles("upper_limits", self.upper_limits, ALL_JOINTS))
        for label, lo, hi in zip(ALL_JOINTS, self.lower_limits, self.upper_limits):
            if not lo < hi:
                raise ValueError(f"lower_limits[{label}] must be below upper_limits[{label}], got {lo} >= {hi}")
            if hi - lo > 2 * np.pi + 1e-12:
                raise ValueError(f"upper_limits[{label}] - lower_limits[{label}] must be at most 360 deg, "
                                 f"got {np.degrees(hi - lo):g} deg")
        choice("redundant_waist", self.redundant_waist, MODES)
        choice("roll_actuator", self.roll_actuator, MODES)


class _Unit:
    """One unit's configuration for a tip point: waist, in-plane five-bar, 3D directions.

    Only what the reach and limit tests (``inverse``, ``feasible``, the dextrous region) read is
    formed when it is built, one whole (...) array per quantity: the waist and shoulder angles.
    The plane frame ``er``, ``n`` (and the sines they come from), the U-joint bend, ``distal`` and
    ``tangent`` (the Jacobian rows' and the roll's inputs) are formed on first use. What depends on
    the waist angle alone (with the pen axis: the bend) is formed on ``waist``'s table when the
    poses fold (``_Waist``).
    """

    def __init__(self, waist: _Waist, u, w, legs, ok, upper_arm: float, shoulders: FloatArray) -> None:
        self.waist = waist
        self.psi = waist.psi    # (...) waist angle
        self.u = u              # (...) in-plane tip coordinate along e_x
        self.w = w              # (...) in-plane tip coordinate along e_r (radial, > 0)
        self.legs = legs        # ((...), (...)) shoulder angles (x = -l1/2 shoulder, x = +l1/2 shoulder)
        self.ok = ok            # (...) both legs reach
        self._upper_arm, self._shoulders = upper_arm, shoulders

    @functools.cached_property
    def sin_cos(self) -> tuple[FloatArray, FloatArray]:
        """``(sin psi, cos psi)``, each (...): ``er = (0, -s, c)``, ``n = e_x x e_r = (0, -c, -s)``."""
        s, c = self.waist.sin_cos
        return self.waist.spread(s), self.waist.spread(c)

    @functools.cached_property
    def bend(self) -> FloatArray:
        """U-joint bend ``angle(p, -n)`` (...), rad."""
        return self.waist.spread(self.waist.bend)

    @functools.cached_property
    def _frame(self) -> tuple[FloatArray, FloatArray]:
        s, c = self.sin_cos
        zero = np.zeros_like(self.psi)
        return np.stack([zero, -s, c], -1), np.stack([zero, -c, -s], -1)

    @property
    def er(self) -> FloatArray:
        """(..., 3) radial direction."""
        return self._frame[0]

    @property
    def n(self) -> FloatArray:
        """(..., 3) plane normal ``e_x x e_r``."""
        return self._frame[1]

    @functools.cached_property
    def theta(self) -> FloatArray:
        """(..., 2) shoulder angles, ``legs`` side by side."""
        return np.stack(self.legs, -1)

    @functools.cached_property
    def _in_plane(self) -> tuple[FloatArray, FloatArray]:
        cos_t, sin_t = np.cos(self.theta), np.sin(self.theta)
        elbows = self._shoulders + self._upper_arm * np.stack([cos_t, sin_t], -1)
        distal = np.stack([self.u, self.w], -1)[..., None, :] - elbows
        return distal, np.stack([-sin_t, cos_t], -1)

    @property
    def distal(self) -> FloatArray:
        """(..., 2, 2) in-plane distal vectors tip - elbow."""
        return self._in_plane[0]

    @property
    def tangent(self) -> FloatArray:
        """(..., 2, 2) in-plane d(cos, sin)/d theta."""
        return self._in_plane[1]


class _Waist:
    """A unit's waist angle and what follows from it and the pen axis, on the poses or on a fold's table.

    ``fold`` (``pose_memo.Fold``): the poses are positions x a repeating block of orientations, and
    the waist depends on the tip's ``y, z`` alone, so it is computed once per distinct position
    ``(y, z)`` and orientation, ``(U, B)``, and spread onto the poses: the same values bit for bit
    (the same operations on the same numbers). Without it the table is the poses.
    """

    def __init__(self, ty: FloatArray, tz: FloatArray, y0: float, p, fold=None) -> None:
        self._fold = fold
        if fold is not None:
            ty, tz = fold.table(ty), fold.table(tz)
            p = tuple(fold.block(c) for c in p)
        dy, dz = ty - y0, tz
        self.psi_table = np.arctan2(-dy, dz)
        self.w_table = np.hypot(dy, dz)
        self._p = p
        self.psi = self.spread(self.psi_table)

    def spread(self, table: FloatArray) -> FloatArray:
        """A table's values on the poses."""
        return table if self._fold is None else self._fold.spread(table)

    @functools.cached_property
    def sin_cos(self) -> tuple[FloatArray, FloatArray]:
        """``(sin psi, cos psi)`` on the table."""
        return np.sin(self.psi_table), np.cos(self.psi_table)

    @functools.cached_property
    def bend(self) -> FloatArray:
        """U-joint bend ``angle(p, -n)`` on the table, rad.

        ``vector_rows.angle_between(p, -n)`` term by term with ``-n = (-0, c, s)``: its terms in
        ``-0`` are signed zeros that change neither ``|p x -n|^2`` nor ``0 + p . -n``, so they are
        left out; the values are the same bit for bit (``tests/kinematics/test_twin_pantograph.py``).
        """
        p0, p1, p2 = self._p
        s, c = self.sin_cos
        c0 = p1 * s - p2 * c
        c1 = p0 * s
        c2 = p0 * c
        square = 0.0 + c0 * c0
        square += c1 * c1
        square += c2 * c2
        dot = 0.0 + p1 * c
        dot += p2 * s
        return np.arctan2(np.sqrt(square), dot)


class _Config:
    """Everything the pose fixes (IK branch of the model): units, pen, wrist.

    The reach and limit tests read whole (...) arrays: the pen axis as its components
    ``p_parts``, the units' angles. The stacked forms (``p``, ``tips``), the pen frame ``rot``
    (5-DOF: formed by ``make_rot``) and the roll wrist's cross axis ``a1`` (5-DOF: only the roll's
    own row of ``_twist_rows`` reads it) are formed on first use.
    """

    def __init__(self, make_rot, p_parts, tip_parts, a: _Unit, b: _Unit, q7, ok, a1=None, rot=None) -> None:
        self._make_rot = make_rot
        self.p_parts = p_parts      # ((...), (...), (...)) pen axis R e_y, by component
        self._tip_parts = tip_parts  # (A, B), each ((...), (...), (...)): U-joint centres by component
        self.a, self.b = a, b
        self.q7 = q7            # (...) roll joint (nan for the 5-DOF task)
        self.ok = ok            # (...) reachable (and the roll wrist not singular, 6-DOF)
        if a1 is not None:
            self.__dict__["a1"] = a1
        if rot is not None:
            self.__dict__["rot"] = rot

    @functools.cached_property
    def rot(self) -> FloatArray:
        """(..., 3, 3) pen frame (tilt only for 5-DOF)."""
        return self._make_rot()

    @functools.cached_property
    def p(self) -> FloatArray:
        """(..., 3) pen axis ``R e_y``."""
        return np.stack(self.p_parts, -1)

    @functools.cached_property
    def tips(self) -> FloatArray:
        """(..., 2, 3) U-joint centres A, B."""
        return np.stack([np.stack(parts, -1) for parts in self._tip_parts], -2)

    @functools.cached_property
    def a1(self) -> FloatArray:
        """(..., 3) U-joint cross axis on the yoke side (roll drive): ``unit(n_A x a2)``."""
        return _cross_axis(self.a.n, self.rot[..., :, 0])[0]


def _cross_axis(n: FloatArray, a2: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``unit(n x a2)`` (..., 3) and ``|n x a2|`` (...)."""
    cross = np.cross(n, a2)
    norm = np.linalg.norm(cross, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return cross / norm[..., None], norm


#: The last ``K`` each thread computed, ``(params, x, K)``: a map asks for ``jacobian`` and
#: ``force_map`` at the same poses, both ``K`` based, and the IK plus twist rows are most of
#: their cost. Keyed on the parameters and the exact pose values (a copy), so a hit returns the
#: same numbers a recomputation would; per thread, so map chunks on the pool do not evict each
#: other; callers get a copy (they may write into it).
_LAST_K = threading.local()
#: The last configuration (``_config``) each thread built, keyed on the model and the exact poses.
_LAST_CONFIG = PoseMemo()
#: Each thread's last ``inverse``: ``(model, poses (a copy), configuration)``. ``metrics.quantities.evaluate``
#: asks ``feasible`` at the reachable ones of the poses it gave ``inverse``: a subset, which
#: ``_LAST_CONFIG`` (exact poses) misses, and the IK was built a second time (``_reached_rows``).
_LAST_INVERSE = threading.local()


class TwinPantograph(ActuatedSubset, MechanismBase):
    """Twin-Pantograph: two waist + five-bar units holding a pen (paper 001). See the module doc."""

    PARAM_INFO = (
        ParamInfo("shoulder_separation", "mm", 1e-3, "l1: distance between a unit's two shoulder joints"),
        ParamInfo("upper_arm", "mm", 1e-3, "l2: proximal (upper arm) link length of each unit"),
        ParamInfo("forearm", "mm", 1e-3, "l3: distal (forearm) link length of each unit"),
        ParamInfo("unit_separation", "mm", 1e-3, "l4: distance between the two units' planes along the pen axis"),
        ParamInfo("pen_length", "mm", 1e-3, "l6: distance between the pen's two U-joint centres"),
        ParamInfo("ujoint_limit", "deg", _DEG, "Largest U-joint bend (pen vs. plane normal)"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous motor torque", ALL_JOINTS),
        ParamInfo("gear_ratios", "", 1.0, "Transmission ratio, joint / motor", ALL_JOINTS),
        ParamInfo("joint_resolution", "deg", _DEG, "One sensor count of the joint", ALL_JOINTS),
        ParamInfo("lower_limits", "deg", _DEG, "Lower joint limit", ALL_JOINTS),
        ParamInfo("upper_limits", "deg", _DEG, "Upper joint limit", ALL_JOINTS),
        ParamInfo("redundant_waist", "", 1.0, "Unit B's waist q4: actuated (redundant) or passive", choices=MODES),
        ParamInfo("roll_actuator", "", 1.0, "Roll drive q7: actuated (6-DOF task) or passive (5-DOF)",
                  choices=MODES),
        ParamInfo("ujoint_lever", "", 1.0, "Each U-joint's distance from the pen's centre, in l6 (0.5: the "
                  "U-joints l6 apart; 1: l6 is the lever, 2 l6 apart)"),
        ParamInfo("reference_along", "", 1.0, "Task point along the pen, in centre-to-U-joint distances "
                  "(0: the centre, -1: unit A's U-joint, +1: unit B's)"),
        ParamInfo("reference_offset", "mm", 1e-3, "Task point's offset across the pen (pen frame z; +z at home)"),
        *mass_param_info(LINKS, "per unit: waist body, each upper arm, forearm (rods), elbow, tip joint, "
                         "counterweight (points); the pen, a rod between the U-joints", ALL_JOINTS),
        ParamInfo("waist_inertia", "g cm^2", G_CM2, "Waist body's principal moments about its centre on the "
                  "waist axis (x: the waist axis)", MOMENTS),
        ParamInfo("counterweight_offset", "mm", 1e-3, "Counterweight's distance behind the shoulder, on the "
                  "upper arm's extension"),
    )
    mass_coordinates = "task"

    def __init__(self, params: TwinPantographParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else TwinPantographParams(**kwargs))

    # -- mass model -------------------------------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the bodies' masses are estimated or given (``mass_model`` not ``"none"``)."""
        return self.params.mass_model != "none"

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """Per unit (A, then B): the waist body, upper arms, forearms (rods along x from the
        motor-side joint), elbows, counterweights and the tip joint; then the pen (a rod along y).
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        m_waist, m_upper, m_fore, m_elbow, m_tip, m_cw, m_pen = p.link_masses
        unit = (Body("waist", m_waist, (0.0, 0.0, 0.0), (*p.waist_inertia, 0.0, 0.0, 0.0)),
                rod("upper_arm", m_upper, p.upper_arm), rod("upper_arm", m_upper, p.upper_arm),
                rod("forearm", m_fore, p.forearm), rod("forearm", m_fore, p.forearm),
                point_mass("elbow", m_elbow), point_mass("elbow", m_elbow),
                point_mass("counterweight", m_cw), point_mass("counterweight", m_cw),
                point_mass("tip", m_tip))
        radius = PEN_RADIUS if self.six_dof else 0.0
        return (*unit, *unit, rod("pen", m_pen, 2.0 * self.half_span, axis=1, radius=radius))

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Frames of ``bodies`` in the base frame, (..., 21, 3, 3) and (..., 21, 3), m, from the pose ``x``.

        A waist body turns with its waist: axes ``(e_x, e_r, n)``, origin the waist centre. Upper
        arm ``j`` runs from shoulder ``j`` to elbow ``j``, forearm ``j`` from elbow ``j`` to the tip
        (``kinematics.mass_params.link_frames`` with the plane normal ``n``); the counterweight of
        shoulder ``j`` sits ``counterweight_offset`` behind it on the line elbow -> shoulder. The
        pen frame is the pose's ``R`` (pen axis ``R e_y``) at unit A's U-joint centre. ``q`` is not
        used: the bodies follow from the pose through the closed-form inverse kinematics.
        """
        if not self.has_mass_model:
            raise self._no_mass_model()
        x = as_points("x", x, self.task_dim)
        cfg = self._config(x)
        p = self.params
        rot, org = [], []
        for unit, base, tip in ((cfg.a, self.unit_bases()[0], cfg.tips[..., 0, :]),
                                (cfg.b, self.unit_bases()[1], cfg.tips[..., 1, :])):
            ex = np.broadcast_to(_EX, unit.er.shape)

            def to3(uw, unit=unit, base=base, ex=ex):
                return base + uw[..., 0:1] * ex + uw[..., 1:2] * unit.er

            shoulders = [to3(np.broadcast_to(s, unit.er.shape[:-1] + (2,))) for s in self._shoulders()]
            elbows = [to3(self._shoulders()[j] + p.upper_arm * np.stack([np.cos(unit.theta[..., j]),
                                                                          np.sin(unit.theta[..., j])], -1))
                      for j in range(2)]
            back = [s - p.counterweight_offset * (e - s) / p.upper_arm for s, e in zip(shoulders, elbows)]
            upper = [link_frames(s, e, unit.n) for s, e in zip(shoulders, elbows)]
            fore = [link_frames(e, tip, unit.n) for e in elbows]
            waist = np.stack([ex, unit.er, unit.n], axis=-1)
            rot += [waist, *upper, *fore, waist, waist, waist, waist, waist]
            org += [np.broadcast_to(base, tip.shape), *shoulders, *elbows, *elbows, *back, tip]
        rot.append(cfg.rot)
        org.append(cfg.tips[..., 0, :])
        rot, org = np.stack(rot, axis=-3), np.stack(org, axis=-2)
        ok = cfg.ok[..., None, None]
        return np.where(ok[..., None], rot, np.nan), np.where(ok, org, np.nan)

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact ``dc_b/dx``, ``dw_b/dx`` (21, 3, m, N), ``R_b`` (21, 3, 3, N) and ``G = dq/dx`` (n, m, N).

        Component-first (``kinematics.bodies``), in the rates of the pose coordinates ``x`` (as
        ``body_poses`` is placed). The pen turns at ``omega = J_l(r) rdot`` (6-DOF; 5-DOF the tilt
        ``J_l([rx, 0, rz])`` on ``(rxdot, rzdot)``), so each U-joint centre moves at
        ``v + omega x r_s`` and the seven joints at ``K6 [v; omega]`` (``_twist_rows``: the loop
        closures of both five-bars, their waists and the roll wrist). A waist body turns about
        ``e_x`` at ``psidot`` (``e_r' = n psidot``, ``n' = -e_r psidot``); elbow j moves at
        ``l2 thetadot_j (-sin theta_j e_x + cos theta_j e_r) + l2 sin theta_j n psidot``.
        """
        x = as_points("x", x, self.task_dim).reshape(-1, self.task_dim)
        m, p = self.task_dim, self.params
        cfg = self._config(x)
        xs, _ = finite_rows(x, self.home_pose())
        twist = np.zeros((len(x), 6, m))
        twist[:, :3, :3] = np.eye(3)
        if self.six_dof:
            twist[:, 3:, 3:] = per_block(left_jacobian, xs[:, 3:6])
        else:
            zero = np.zeros(len(x))
            twist[:, 3:, 3:] = per_block(left_jacobian, np.stack([xs[:, 3], zero, xs[:, 4]], -1))[:, :, [0, 2]]
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            rates = columns(self._twist_rows(cfg) @ twist)                              # (7, m, N)
        twist = columns(twist)                                                          # (6, m, N)
        pen = columns(cfg.rot)
        offsets = columns(self.tip_offsets(cfg.rot))                                   # (2, 3, N)
        tips = columns(cfg.tips)
        n_pts = x.shape[0]
        ex = np.broadcast_to(_EX[:, None], (3, n_pts))
        still = np.zeros((3, m, n_pts))
        parts = []
        for k, (unit, base) in enumerate(((cfg.a, self.unit_bases()[0]), (cfg.b, self.unit_bases()[1]))):
            er, nrm = columns(unit.er), columns(unit.n)
            theta = columns(unit.theta)
            dpsi = rates[3 * k]
            der = nrm[:, None] * dpsi
            dtip = twist[:3] + cross3(twist[3:], offsets[k][:, None])
            waist = (np.stack([ex, er, nrm], axis=1), ex[:, None] * dpsi, still)          # turns about e_x
            shoulders = [base[:, None] + s[0] * ex + s[1] * er for s in self._shoulders()]
            dshoulders = [s[1] * der for s in self._shoulders()]
            elbows, delbows = [], []
            for j in range(2):
                c, s_ = np.cos(theta[j]), np.sin(theta[j])
                sx, sw = self._shoulders()[j][:, None] + p.upper_arm * np.stack([c, s_])
                elbows.append(base[:, None] + sx * ex + sw * er)
                delbows.append(p.upper_arm * (-s_ * ex + c * er)[:, None] * rates[3 * k + 1 + j] + sw * der)
            backs = [-(p.counterweight_offset / p.upper_arm) * (de - ds) + ds for ds, de in zip(dshoulders, delbows)]
            # The unit's plane turns with its waist: each link at that rate plus its in-plane one.
            upper = [plane_link_part(a, b, nrm, da, db, waist[1])
                     for a, b, da, db in zip(shoulders, elbows, dshoulders, delbows)]
            fore = [plane_link_part(e, tips[k], nrm, de, dtip, waist[1]) for e, de in zip(elbows, delbows)]
            moved = [(waist[0], waist[1], d) for d in (*delbows, *backs, dtip)]
            parts += [waist, *upper, *fore, *moved]
        parts.append((pen, twist[3:], twist[:3] + cross3(twist[3:], offsets[0][:, None])))
        jv, jw, rot = stack_bodies(parts, body_arrays(self.bodies())[1])
        ok = cfg.ok
        if not np.all(ok):
            # Body by body: np.where on the lists would first copy them into one (k, 3, d, N) array.
            jv, jw, rot = ([np.where(ok, a, np.nan) for a in arrays] for arrays in (jv, jw, rot))
        return jv, jw, rot, rates[list(self.actuated)]

    # -- configuration ---------------------------------------------------------------------
    @property
    def six_dof(self) -> bool:
        """The roll drive is actuated, so the task includes roll (6-DOF).

        Returns
        -------
        bool
        """
        return self.params.roll_actuator == "active"

    @property
    def actuated(self) -> tuple[int, ...]:
        """Indices into ``ALL_JOINTS`` of the actuated joints.

        Returns
        -------
        tuple of int, length ``n``

        Examples
        --------
        >>> TwinPantograph().actuated
        (0, 1, 2, 3, 4, 5)
        """
        idx = [0, 1, 2]
        if self.params.redundant_waist == "active":
            idx.append(3)
        idx += [4, 5]
        if self.six_dof:
            idx.append(6)
        return tuple(idx)

    @property
    def n_joints(self) -> int:
        """``n``, the number of actuated joints (5 to 7, by actuation)."""
        return len(self.actuated)

    @property
    def task_dim(self) -> int:
        """``m``: 6 with the roll actuated, else 5."""
        return 6 if self.six_dof else 5

    @property
    def redundant(self) -> bool:
        """Same as ``is_redundant``: more actuators than task coordinates (use ``force_map``, a zonotope).

        Returns
        -------
        bool
        """
        return self.is_redundant

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the actuated joints, a selection of ``ALL_JOINTS``."""
        return tuple(ALL_JOINTS[i] for i in self.actuated)

    @property
    def task_names(self) -> tuple[str, ...]:
        """``("x", "y", "z", "rx", "ry", "rz")`` (6-DOF) or ``("x", "y", "z", "rx", "rz")`` (5-DOF)."""
        return ("x", "y", "z", "rx", "ry", "rz") if self.six_dof else ("x", "y", "z", "rx", "rz")

    @property
    def task_units(self) -> tuple[str, ...]:
        """``"m"`` for the pen centre, ``"rad"`` for the orientation coordinates."""
        return ("m", "m", "m") + ("rad",) * (self.task_dim - 3)

    @property
    def characteristic_length(self) -> float:
        """Moment arm (m) for comparing moments with forces: ``half_span`` (default ``l6 / 2``).

        The pen is tilted by opposite forces at its two U-joints, ``l6 / 2`` from its centre,
        so a moment over this length is the tip force that holds it (``metrics.wrenches``:
        the condition number's task scaling). Paper 001 Table I's bending moments per unit
        hand force, 3.6 and 3.9 cm, are of the same order.
        """
        return self.half_span

    @property
    def half_span(self) -> float:
        """``h``, each U-joint's distance from the pen's centre (m): ``ujoint_lever * l6`` (default ``l6 / 2``).

        Returns
        -------
        float
            m.
        """
        return self.params.ujoint_lever * self.params.pen_length

    def tip_offsets(self, rot: ArrayLike) -> FloatArray:
        """U-joint centres A, B relative to the task point, (..., 2, 3), m, for pen frames ``rot`` (..., 3, 3).

        ``r_s = (s - reference_along) h p - reference_offset b`` with ``s = -1`` (A), ``+1`` (B),
        ``p = R e_y`` the pen axis, ``b = R e_z`` and ``h`` = ``half_span``.

        Parameters
        ----------
        rot : array_like, shape (..., 3, 3)
            Pen frames.

        Returns
        -------
        ndarray, shape (..., 2, 3)
            m.
        """
        rot = np.asarray(rot, dtype=float)
        p, b = rot[..., :, 1], rot[..., :, 2]
        h, along, off = self.half_span, self.params.reference_along, self.params.reference_offset
        tips = []
        for s in (-1.0, 1.0):
            r = ((s - along) * h) * p if along else (s * h) * p
            if off:
                r = r - off * b
            tips.append(r)
        return np.stack(tips, -2)

    def unit_bases(self) -> FloatArray:
        """Waist centres of unit A and unit B (the shoulders' midpoints), (2, 3).

        Returns
        -------
        ndarray, shape (2, 3)
            m.
        """
        half = 0.5 * self.params.unit_separation
        return np.array([[0.0, -half, 0.0], [0.0, half, 0.0]])

    def home_pose(self, distance: float = 0.25) -> FloatArray:
        """The pen centred at ``(0, 0, distance)`` along ``y``, zero orientation, (m,).

        Parameters
        ----------
        distance : float
            Distance of the pen centre along ``z``, m.

        Returns
        -------
        ndarray, shape (m,)
            m and rad.

        Examples
        --------
        >>> TwinPantograph().home_pose().tolist()
        [0.0, 0.0, 0.25, 0.0, 0.0]
        """
        return np.array([0.0, 0.0, float(distance)] + [0.0] * (self.task_dim - 3))

    # -- pieces -----------------------------------------------------------------------------
    def _rotation(self, x: FloatArray, period: int | None | bool = True) -> FloatArray:
        """Pen frames (..., 3, 3) of poses ``x`` (..., m), once per orientation of a repeating block.

        A map holds the orientation fixed over its grid, and the dextrous region tests a block of
        orientations at every position: ``pose_memo.per_block`` computes the block's frames and
        repeats them, the same values at a fraction of the cost.
        """
        return per_block(self._frames, x[..., 3:], period)

    def _frames(self, angles: FloatArray) -> FloatArray:
        return rotation_matrix(angles) if self.six_dof else tilt_matrix(angles)

    def _plane_frame(self, psi: FloatArray) -> tuple[FloatArray, FloatArray]:
        s, c = np.sin(psi), np.cos(psi)
        zero = np.zeros_like(psi)
        er = np.stack([zero, -s, c], -1)
        n = np.stack([zero, -c, -s], -1)           # e_x x e_r
        return er, n

    def _shoulders(self) -> FloatArray:
        a = 0.5 * self.params.shoulder_separation
        return np.array([[-a, 0.0], [a, 0.0]])

    def _unit_inverse(self, tip: tuple[FloatArray, FloatArray, FloatArray], y0: float, p, fold=None) -> _Unit:
        """Waist (front branch) and five-bar (elbows outward) reaching ``tip``, its components (...) each.

        ``p``: the pen axis by component (for the bend); ``fold``: ``_Waist``'s.
        """
        l2, l3 = self.params.upper_arm, self.params.forearm
        u, ty, tz = tip
        waist = _Waist(ty, tz, y0, p, fold)
        w = waist.spread(waist.w_table)
        shoulders = self._shoulders()
        # One leg at a time, on whole (...) arrays: the same operations as on (..., 2) pairs, with
        # no strided halves.
        legs, ok = [], None
        for (sx, sw), elbow in zip(shoulders, (1.0, -1.0)):
            du, dw = u - sx, w - sw
            rho = np.hypot(du, dw)
            with np.errstate(divide="ignore", invalid="ignore"):
                cos_e = (l2 * l2 + rho * rho - l3 * l3) / (2.0 * l2 * rho)
            reach = np.abs(cos_e) <= 1.0 + _SLACK
            ok = reach if ok is None else ok & reach
            legs.append((du, dw, cos_e, elbow))
        # The angles where the unit reaches: every result that reads them elsewhere is masked by
        # ``ok`` (``nan``). Where most poses are out of reach (a box's faces, the zero-orientation
        # pass of a dextrous region) only those are computed.
        few = ok.ndim and np.count_nonzero(ok) < 0.5 * ok.size
        theta = []
        for du, dw, cos_e, elbow in legs:
            if few:
                angle = np.full(ok.shape, np.nan)
                angle[ok] = np.arctan2(dw[ok], du[ok]) + elbow * np.arccos(np.clip(cos_e[ok], -1.0, 1.0))
            else:
                angle = np.arctan2(dw, du) + elbow * np.arccos(np.clip(cos_e, -1.0, 1.0))
            theta.append(angle)
        return _Unit(waist, u, w, tuple(theta), ok, l2, shoulders)

    def _five_bar_tip(self, theta: FloatArray) -> tuple[FloatArray, FloatArray, BoolArray]:
        """In-plane tip ``(u, w)`` of shoulder angles (..., 2), assembly beyond the elbows."""
        l2, l3 = self.params.upper_arm, self.params.forearm
        elbows = self._shoulders() + l2 * np.stack([np.cos(theta), np.sin(theta)], -1)
        chord = elbows[..., 1, :] - elbows[..., 0, :]
        half = 0.5 * np.hypot(chord[..., 0], chord[..., 1])
        height_sq = l3 * l3 - half * half
        ok = height_sq >= 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            unit = chord / (2.0 * half[..., None])
        normal = np.stack([-unit[..., 1], unit[..., 0]], -1)         # left of elbow(q2) -> elbow(q3)
        tip = 0.5 * (elbows[..., 0, :] + elbows[..., 1, :]) + np.sqrt(np.maximum(height_sq, 0.0))[..., None] * normal
        return tip[..., 0], tip[..., 1], ok

    def _unit_point(self, y0: float, psi: FloatArray, u: FloatArray, w: FloatArray) -> FloatArray:
        er, _ = self._plane_frame(psi)
        return np.array([0.0, y0, 0.0]) + u[..., None] * _EX + w[..., None] * er

    def _config(self, x: FloatArray) -> _Config:
        """IK of the whole device at poses ``x`` (..., m); non-finite poses are not ``ok``.

        The last batch's is kept (``_LAST_CONFIG``): ``inverse`` and ``feasible`` at the same poses
        (``metrics.dextrous``), or ``jacobian`` and ``body_velocities``, build it once. Read-only.
        """
        x = np.asarray(x, dtype=float)
        cfg = _LAST_CONFIG.get(self, x)
        return cfg if cfg is not None else _LAST_CONFIG.put(self, x, self._build_config(x))

    def _build_config(self, x: FloatArray) -> _Config:
        x = np.asarray(x, dtype=np.float64)
        if np.isfinite(x).all():        # finite_rows' answer, without its reduction along the short last axis
            finite = np.ones(x.shape[:-1], bool)
        else:
            x, finite = finite_rows(x, self.home_pose())
        # The orientations' period in the batch (``pose_memo``): found once, read by the frames and the fold.
        period = pose_memo.repeat_period(x.reshape(-1, x.shape[-1])[:, 3:])
        rot = None
        if self.six_dof or self.params.reference_offset:
            rot = self._rotation(x, period)
            p = tuple(rot[..., k, 1] for k in range(3))
        else:
            p = self._pen_axis(x, period)
        tips = self._tip_parts(x, p, rot)
        (ya, yb) = self.unit_bases()[:, 1]
        # Positions x a block of orientations (the dextrous region's batches): the waists per
        # distinct position (y, z) and orientation (``_Waist``).
        fold = fold_rows(x, slice(3, None), slice(0, 3), slice(1, 3), period=period) if x.ndim > 1 else None
        ua = self._unit_inverse(tips[0], ya, p, fold)
        ub = self._unit_inverse(tips[1], yb, p, fold)
        ok = ua.ok & ub.ok & finite

        def make_rot(x=x):
            return self._rotation(x)

        if not self.six_dof:
            return _Config(make_rot, p, tips, ua, ub, np.full(x.shape[:-1], np.nan), ok, rot=rot)
        a1, norm = _cross_axis(ua.n, rot[..., :, 0])
        ok = ok & (norm > 1e-12)
        f = self._forearm_a(ua)
        q7 = np.arctan2(np.sum(np.cross(f, a1) * ua.n, -1), np.sum(f * a1, -1))
        return _Config(make_rot, p, tips, ua, ub, q7, ok, a1, rot=rot)

    def _pen_axis(self, x: FloatArray, period: int | None | bool = True) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The pen axis ``R e_y`` of poses ``x`` (..., m) by component, each (...), as ``_rotation`` gives it."""
        def axis(angles):
            frames = self._frames(angles)
            return tuple(np.array(frames[..., k, 1]) for k in range(3))

        return per_block(axis, x[..., 3:], period)

    def _tip_parts(self, x: FloatArray, p, rot) -> tuple[tuple[FloatArray, ...], tuple[FloatArray, ...]]:
        """U-joint centres A, B by component: ``x[..., :3] + tip_offsets(rot)``, term by term."""
        h, along, off = self.half_span, self.params.reference_along, self.params.reference_offset
        tips = []
        for s in (-1.0, 1.0):
            coef = (s - along) * h if along else s * h
            parts = []
            for k in range(3):
                r = coef * p[k]
                if off:
                    r = r - off * rot[..., k, 2]
                parts.append(x[..., k] + r)
            tips.append(tuple(parts))
        return tips[0], tips[1]

    def _forearm_a(self, unit: _Unit) -> FloatArray:
        """Unit direction of unit A's q2 forearm (elbow -> tip), (..., 3): the roll drive's base."""
        d = unit.distal[..., 0, :] / self.params.forearm
        return d[..., 0:1] * _EX + d[..., 1:2] * unit.er

    def _joints(self, cfg: _Config, which=range(7)) -> FloatArray:
        """Joints ``which`` of all seven (..., len(which)), wrapped into their limits where possible."""
        raw = (cfg.a.psi, *cfg.a.legs, cfg.b.psi, *cfg.b.legs, cfg.q7)
        lo, hi = self.params.lower_limits, self.params.upper_limits
        out = np.empty(cfg.ok.shape + (len(which),))
        for k, i in enumerate(which):
            out[..., k] = wrap_into(raw[i], lo[i], hi[i])[0]
        out[~cfg.ok] = np.nan
        return out

    # -- kinematics -------------------------------------------------------------------------
    def all_joints(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """All seven joints ``q1..q7`` (..., 7) at poses ``x`` (..., m), passive ones included.

        ``q7`` is ``nan`` for the 5-DOF task (the pen's roll is not set). Unreachable: ``nan``.

        Parameters
        ----------
        x : array_like, shape (..., m)
            Poses, m and rad.

        Returns
        -------
        q : ndarray, shape (..., 7)
            rad.
        reachable : ndarray of bool, shape (...)
        """
        x = as_points("x", x, self.task_dim)
        cfg = self._config(x)
        return self._joints(cfg), cfg.ok

    def inverse(self, x: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Actuated joints ``q`` (..., n) reaching poses ``x`` (..., m), and ``reachable`` (...).

        Closed form, branch as in the module doc. Angles are shifted by multiples of 2 pi into
        their limits where they fit (limits are checked by ``feasible``).

        Examples
        --------
        >>> mech = TwinPantograph()
        >>> q, ok = mech.inverse(mech.home_pose())
        >>> q.shape, bool(ok)
        ((6,), True)
        """
        x = as_points("x", x, self.task_dim)
        cfg = self._config(x)
        _LAST_INVERSE.entry = (self, np.array(x, dtype=np.float64), cfg)
        return self._joints(cfg, self.actuated), cfg.ok

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Pose ``x`` (..., m) of actuated joints ``q`` (..., n), and whether it assembles.

        Closed form. Unit A's tip from ``q1..q3``. Unit B's tip from ``q4..q6`` if its waist is
        actuated (then ``ok`` also requires the tips to be ``l6`` apart within
        ``CONSISTENCY_TOL``: redundant joints must agree); with a passive waist, ``q4`` is the
        root of ``|T_B(q4) - T_A| = l6`` with the smaller angle ``q4`` (the pen points from
        A towards B's side: the IK branch). Roll from ``q7`` for the 6-DOF task.

        Examples
        --------
        >>> mech = TwinPantograph()
        >>> q, _ = mech.inverse(mech.home_pose())
        >>> x, ok = mech.forward(q)
        >>> bool(np.allclose(x, mech.home_pose(), rtol=0.0, atol=1e-12)), bool(ok)
        (True, True)
        """
        q, finite = finite_rows(as_points("q", q, self.n_joints), 0.0)
        full = np.full(q.shape[:-1] + (7,), np.nan)
        full[..., list(self.actuated)] = q
        (ya, yb) = self.unit_bases()[:, 1]
        ua, wa, ok_a = self._five_bar_tip(full[..., 1:3])
        ub, wb, ok_b = self._five_bar_tip(full[..., 4:6])
        tip_a = self._unit_point(ya, full[..., 0], ua, wa)
        l6 = 2.0 * self.half_span            # the U-joints' separation (l6 with the default lever)
        ok = ok_a & ok_b & finite
        if self.params.redundant_waist == "active":
            tip_b = self._unit_point(yb, full[..., 3], ub, wb)
            span = np.linalg.norm(tip_b - tip_a, axis=-1)
            ok &= np.abs(span - l6) <= CONSISTENCY_TOL * l6
        else:
            d = tip_a - np.array([0.0, yb, 0.0])
            rho = np.hypot(d[..., 1], d[..., 2])
            psi0 = np.arctan2(-d[..., 1], d[..., 2])
            with np.errstate(divide="ignore", invalid="ignore"):
                cos_d = ((ub - d[..., 0]) ** 2 + wb * wb + rho * rho - l6 * l6) / (2.0 * wb * rho)
            ok &= np.abs(cos_d) <= 1.0 + _SLACK
            tip_b = self._unit_point(yb, psi0 - np.arccos(np.clip(cos_d, -1.0, 1.0)), ub, wb)
            span = np.linalg.norm(tip_b - tip_a, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            p = (tip_b - tip_a) / span[..., None]
        centre = 0.5 * (tip_a + tip_b)
        if self.six_dof:
            psi_a = full[..., 0]
            er, n = self._plane_frame(psi_a)
            shoulder = self._shoulders()[0]
            l2 = self.params.upper_arm
            elbow = shoulder + l2 * np.stack([np.cos(full[..., 1]), np.sin(full[..., 1])], -1)
            dist = (np.stack([ua, wa], -1) - elbow) / self.params.forearm
            f = dist[..., 0:1] * _EX + dist[..., 1:2] * er
            q7 = full[..., 6:7]
            a1 = np.cos(q7) * f + np.sin(q7) * np.cross(n, f)
            a2 = np.cross(p, a1)
            norm = np.linalg.norm(a2, axis=-1)
            ok &= norm > 1e-12
            with np.errstate(divide="ignore", invalid="ignore"):
                a2 = a2 / norm[..., None]
            a2 = np.where((np.sum(np.cross(n, a2) * a1, -1) < 0)[..., None], -a2, a2)
            rot = np.stack([a2, p, np.cross(a2, p)], -1)
            orient = rotation_vector(np.where(ok[..., None, None], rot, np.eye(3)))
        else:
            orient = tilt_of_direction(p)
            rot = tilt_matrix(orient) if self.params.reference_offset else None
        along, off = self.params.reference_along, self.params.reference_offset
        if along:
            centre = centre + (along * self.half_span) * p
        if off:
            centre = centre + off * rot[..., :, 2]
        x = np.concatenate([centre, orient], -1)
        return np.where(ok[..., None], x, np.nan), ok

    # -- velocities and statics -------------------------------------------------------------
    def _twist_rows(self, cfg: _Config) -> FloatArray:
        """``K6`` (..., 7, 6): rates of all seven joints per pen twist ``[v; omega]`` (base frame).

        Unit joint rates per tip velocity ``Tdot``: waist ``n . Tdot / w``; shoulder j
        ``D_j . Tdot / (l2 d_j . t_j)`` with ``D_j`` the 3D distal vector, ``d_j``, ``t_j`` its
        in-plane form and the proximal link's tangent (from ``|T - E_j| = l3``). Tip velocity
        ``Tdot = v + omega x r_s`` with ``r_s`` the tip's offset from the task point
        (``tip_offsets``; default ``s l6/2 p``, ``s = -1`` (A), ``+1`` (B)), so a gradient ``g`` of
        ``Tdot`` gives the row ``[g, r_s x g]`` (default ``[g, -s (l6/2) g x p]``). Roll: ``omega_pen - omega_forearm =
        q7dot n + alphadot a1 + betadot a2`` (wrist axes), dotted with ``a1 x a2``; ``nan`` for the
        5-DOF task, whose roll is no joint.
        """
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._twist_rows_unguarded(cfg)

    def _twist_rows_unguarded(self, cfg: _Config) -> FloatArray:
        l2, l3 = self.params.upper_arm, self.params.forearm
        h, along, off = self.half_span, self.params.reference_along, self.params.reference_offset
        p = cfg.p
        b = cfg.rot[..., :, 2]
        rows = []
        unit_rows = []
        for unit, s in ((cfg.a, -1.0), (cfg.b, 1.0)):
            lever = (s - along) * h if along else s * h

            def row(g, lever=lever):
                # Tdot = v + omega x r, r = lever p - off b (tip_offsets): the row is [g, r x g]
                moment = -lever * np.cross(g, p)
                if off:
                    moment = moment + off * np.cross(g, b)
                return np.concatenate([g, moment], -1)

            r_psi = row(unit.n / unit.w[..., None])
            denom = l2 * np.sum(unit.distal * unit.tangent, -1)              # (..., 2)
            d3 = unit.distal[..., :, 0:1] * _EX + unit.distal[..., :, 1:2] * unit.er[..., None, :]
            r_th = [row(d3[..., j, :] / denom[..., j, None]) for j in range(2)]
            rows += [r_psi] + r_th
            if self.six_dof:            # the roll's row below needs unit A's
                unit_rows.append((r_psi, r_th, row(np.broadcast_to(_EX, p.shape)), row(unit.er)))
        if not self.six_dof:            # no roll joint: its row is never read
            rows.append(np.full(rows[0].shape, np.nan))
            return np.stack(rows, -2)
        # Roll joint q7 on unit A's q2 forearm.
        r_psi, r_th, r_u, r_w = unit_rows[0]
        unit = cfg.a
        dist, tang = unit.distal[..., 0, :], unit.tangent[..., 0, :]
        rdot_u = r_u - l2 * tang[..., 0:1] * r_th[0]
        rdot_w = r_w - l2 * tang[..., 1:2] * r_th[0]
        r_forearm = (dist[..., 0:1] * rdot_w - dist[..., 1:2] * rdot_u) / (l3 * l3)
        omega_f = _EX[:, None] * r_psi[..., None, :] + unit.n[..., :, None] * r_forearm[..., None, :]   # (..., 3, 6)
        a2 = cfg.rot[..., :, 0]
        m = np.cross(cfg.a1, a2)
        zero = np.zeros_like(m)
        r7 = (np.concatenate([zero, m], -1) - np.einsum("...i,...ij->...j", m, omega_f)) \
            / np.sum(unit.n * m, -1)[..., None]
        rows.append(r7)
        return np.stack(rows, -2)

    def _task_basis(self, cfg: _Config, x: FloatArray) -> FloatArray:
        """``E`` (..., 6, m): the twist ``[v; omega]`` of a task velocity ``xi`` (5-DOF: omega across the pen).

        5-DOF with a task point off the pen's axis (``reference_offset``): the point is fixed in the
        tilt frame ``R = exp([rx, 0, rz]x)``, whose angular velocity also has a component along
        the pen, ``omega . p = c . (omega . a, omega . b)`` with ``c = p^T W (B W)^-1`` (``W`` the
        tilt rates' angular velocity, ``B = [a; b]``): it moves an off-axis point, so ``E`` carries it.
        On the axis it moves nothing and is left out (the default, unchanged).
        """
        batch = cfg.p.shape[:-1]
        if self.six_dof:
            return np.broadcast_to(np.eye(6), batch + (6, 6))
        e = np.zeros(batch + (6, 5))
        e[..., :3, :3] = np.eye(3)
        e[..., 3:, 3] = cfg.rot[..., :, 0]
        e[..., 3:, 4] = cfg.rot[..., :, 2]
        if self.params.reference_offset:
            xs, _ = finite_rows(x, self.home_pose())
            zero = np.zeros(batch)
            w = left_jacobian(np.stack([xs[..., 3], zero, xs[..., 4]], -1))[..., :, [0, 2]]     # (..., 3, 2)
            basis = np.stack([cfg.rot[..., :, 0], cfg.rot[..., :, 2]], -2)                       # (..., 2, 3)
            inv, _ = batched_inverse(basis @ w)
            c = np.einsum("...i,...ij,...jk->...k", cfg.p, w, inv)                               # (..., 2)
            e[..., 3:, 3:] += cfg.p[..., :, None] * c[..., None, :]
        return e

    def _pose(self, q: ArrayLike, x: ArrayLike | None) -> FloatArray:
        if x is None:
            x, _ = self.forward(q)
        return as_points("x", x, self.task_dim)

    def inverse_jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``K`` (..., n, m) with ``qdot = K xi`` (twist ``xi`` as in the module doc), rad per m or rad.

        ``x`` is the pose of ``q`` (computed by ``forward`` when not given); the IK branch of
        the model is used. Entries are ``inf``/``nan`` at an inverse singularity (a five-bar
        leg stretched or folded, a tip on its waist axis, the roll wrist at 90 deg).

        Parameters
        ----------
        q : array_like, shape (..., n)
            Actuated joints, rad.
        x : array_like, shape (..., m), optional
            The pose of ``q``.

        Returns
        -------
        ndarray, shape (..., n, m)
        """
        x = self._pose(q, x)
        memo = getattr(_LAST_K, "entry", None)
        if (memo is not None and memo[0] == self.params and memo[1].shape == x.shape
                and np.array_equal(memo[1], x, equal_nan=True)):
            return memo[2].copy()
        cfg = self._config(x)
        k6 = self._twist_rows(cfg)[..., list(self.actuated), :]
        with np.errstate(invalid="ignore", over="ignore"):
            k = k6 @ self._task_basis(cfg, x)
        k = np.where(cfg.ok[..., None, None], k, np.nan)
        _LAST_K.entry = (self.params, np.array(x), k.copy())
        return k

    def force_map(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``A = K^T`` (..., m, n): the task wrench ``w = A tau`` held by joint torques ``tau``."""
        return np.swapaxes(self.inverse_jacobian(q, x), -1, -2)

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J`` (..., m, n) with ``xi = J qdot`` for consistent joint rates; ``tau = J^T w``.

        Square actuation: ``K^-1`` (``inf`` where ``K`` is singular, e.g. the passive-waist
        singularity when the pen lies in unit B's plane). Redundant: ``K^+ = (K^T K)^-1 K^T``.

        Examples
        --------
        >>> mech = TwinPantograph()
        >>> x = mech.home_pose()
        >>> q, _ = mech.inverse(x)
        >>> mech.jacobian(q, x).shape
        (5, 6)
        """
        k = self.inverse_jacobian(q, x)
        if not self.redundant:
            inv, _ = batched_inverse(k)
            return inv
        kt = np.swapaxes(k, -1, -2)
        with np.errstate(invalid="ignore", over="ignore"):
            inv, _ = spd_inverse(kt @ k)
            return inv @ kt

    def coordinate_rates_to_twist(self, x: ArrayLike) -> FloatArray:
        """``T`` (..., m, m) with ``xi = T @ d(x)/dt``: task coordinate rates -> twist.

        6-DOF: ``blockdiag(I, J_l(r))`` (``rotations.left_jacobian``). 5-DOF: the tilt's
        angular velocity ``J_l([rx, 0, rz]) [rxdot, 0, rzdot]`` projected on ``a = R e_x``,
        ``b = R e_z``.

        Parameters
        ----------
        x : array_like, shape (..., m)
            Poses, m and rad.

        Returns
        -------
        ndarray, shape (..., m, m)
            ``nan`` where ``x`` is not finite.
        """
        x, finite = finite_rows(as_points("x", x, self.task_dim), self.home_pose())
        t = np.zeros(x.shape[:-1] + (self.task_dim, self.task_dim))
        t[..., :3, :3] = np.eye(3)
        if self.six_dof:
            t[..., 3:, 3:] = left_jacobian(x[..., 3:6])
        else:
            zero = np.zeros(x.shape[:-1])
            jl = left_jacobian(np.stack([x[..., 3], zero, x[..., 4]], -1))[..., :, [0, 2]]   # (..., 3, 2)
            rot = tilt_matrix(x[..., 3:5])
            basis = np.stack([rot[..., :, 0], rot[..., :, 2]], -2)                          # (..., 2, 3)
            t[..., 3:, 3:] = basis @ jl
        return np.where(finite[..., None, None], t, np.nan)

    # -- limits -----------------------------------------------------------------------------
    def bend_angles(self, x: ArrayLike) -> FloatArray:
        """U-joint bend at unit A and unit B (..., 2), rad: ``angle(p, -n_k)``, 0 at home.

        Parameters
        ----------
        x : array_like, shape (..., m)
            Poses, m and rad.

        Returns
        -------
        ndarray, shape (..., 2)
            rad.
        """
        x = as_points("x", x, self.task_dim)
        cfg = self._config(x)
        bends = np.stack([cfg.a.bend, cfg.b.bend], -1)
        return np.where(np.all(np.isfinite(x), -1)[..., None], bends, np.nan)

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Reach, joint limits of all joints (passive ones too) and U-joint bends, shape (...).

        ``x`` (the pose of ``q``) is computed by ``forward`` when not given; the passive
        joints' angles come from it.
        """
        q = as_points("q", q, self.n_joints)
        x = self._pose(q, x)
        rows = self._reached_rows(x)
        if rows is None:
            cfg = self._config(x)
            rows = ...                  # every row (0-d poses too)
        else:
            cfg = _LAST_INVERSE.entry[2]
        checked = range(7) if self.six_dof else range(6)
        # The actuated joints are the given q; only the passive ones come from the pose.
        passive = [i for i in checked if i not in self.actuated]
        values = {i: q[..., k] for k, i in enumerate(self.actuated)}
        if passive:
            values.update(zip(passive, np.moveaxis(self._joints(cfg, passive)[rows], -1, 0)))
        p = self.params
        with np.errstate(invalid="ignore"):
            # np.all(np.isfinite(q), axis=-1) column by column: a reduction along the short last axis is slow.
            ok = cfg.ok[rows] & np.isfinite(q[..., 0])
            for k in range(1, q.shape[-1]):
                ok &= np.isfinite(q[..., k])
            for i in checked:
                ok &= (values[i] >= p.lower_limits[i]) & (values[i] <= p.upper_limits[i])
            ok &= (cfg.a.bend[rows] <= p.ujoint_limit) & (cfg.b.bend[rows] <= p.ujoint_limit)
        return ok

    def _reached_rows(self, x: FloatArray) -> np.ndarray | None:
        """Where the last ``inverse``'s poses reached, if ``x`` (k, m) is exactly those rows; else ``None``.

        Its configuration then holds ``x``'s: the same operations on the same numbers, elementwise
        (``_Waist``'s fold included: a waist per distinct position and orientation), so the same
        values as one built at ``x`` alone. Checked bit for bit, as ``PoseMemo``.
        """
        entry = getattr(_LAST_INVERSE, "entry", None)
        if entry is None or entry[0] is not self or x.ndim != 2 or entry[1].ndim != 2:
            return None
        ok = entry[2].ok
        if ok.shape != entry[1].shape[:1] or np.count_nonzero(ok) != len(x) or ok.all():
            return None         # all reached: x is the poses themselves, which _LAST_CONFIG holds
        reached = entry[1][ok]
        if not np.array_equal(reached.view(np.int64), np.ascontiguousarray(x, dtype=np.float64).view(np.int64)):
            return None
        return ok

    # -- drawing ----------------------------------------------------------------------------
    def link_points(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """One polyline through every link, (..., 16, 3), m (the pen is traced twice).

        Points: waist centre A, q2 shoulder, q2 elbow, T_A, T_B, q5 elbow, q5 shoulder, waist
        centre B, q6 shoulder, q6 elbow, T_B, T_A, q3 elbow, q3 shoulder, waist centre A,
        waist centre B (``T`` the U-joint centres; the last segment is the base between the
        units). ``x`` is the pose of ``q`` (computed when not given).
        """
        x = self._pose(q, x)
        cfg = self._config(x)
        l2 = self.params.upper_arm
        pts = {}
        for name, unit, base in (("A", cfg.a, self.unit_bases()[0]), ("B", cfg.b, self.unit_bases()[1])):
            sh = self._shoulders()
            elbows = sh + l2 * np.stack([np.cos(unit.theta), np.sin(unit.theta)], -1)

            def to3(uw, unit=unit, base=base):
                return base + uw[..., 0:1] * _EX + uw[..., 1:2] * unit.er

            pts[name + "0"] = np.broadcast_to(base, unit.er.shape)
            for j in range(2):
                pts[f"{name}{j}s"] = to3(np.broadcast_to(sh[j], elbows[..., j, :].shape), unit=unit)
                pts[f"{name}{j}e"] = to3(elbows[..., j, :], unit=unit)
        ta, tb = cfg.tips[..., 0, :], cfg.tips[..., 1, :]
        seq = [pts["A0"], pts["A0s"], pts["A0e"], ta, tb, pts["B0e"], pts["B0s"], pts["B0"], pts["B1s"],
               pts["B1e"], tb, ta, pts["A1e"], pts["A1s"], pts["A0"], pts["B0"]]
        out = np.stack(seq, -2)
        return np.where(cfg.ok[..., None, None], out, np.nan)
