"""Serial RRR arm with a parallelogram drive: the PHANToM / Touch family.

A base yaw joint ``q1`` about the vertical z axis of frame {0} carries a shoulder joint
``q2`` (the elevation of the first link above the horizontal) and a second link driven
through a parallelogram from a motor on the base, so that ``q3`` is the *absolute* angle of
the second link (measured from straight down, positive towards the radial direction), not
its angle relative to the first link. The conventions, the numbers of the default
parameters and the frame are those of the PHANToM Premium model of ``mahilab/Phantom``
(``cpp/src/PhantomModel.hpp`` and ``PhantomModel.cpp``):

    r = l1 cos q2 + l2 sin q3,     P = (r cos q1,  r sin q1,  l1 sin q2 - l2 cos q3),

with frame {0} at the intersection of the base and shoulder axes, x forward, z up. At
``q = 0`` the first link is horizontal, the second hangs straight down, and the tip is at
``(l1, 0, -l2)``. The joint limits include the coupling limits of the parallelogram,
``q2 - q3 <= max_q2_minus_q3`` and ``q3 - q2 <= max_q3_minus_q2``; they also fix the elbow
branch (``q3 - q2`` stays within 90 deg, so the elbow is never straight or folded flat), and
the only singularity left is the base axis ``r = 0``: ``det J = l1 l2 r cos(q2 - q3)``.

The Jacobian is with respect to the output-side joint angles ``q`` (rad, after the capstans),
output in m; an actuator's joint torque limit is ``motor_torque * gear_ratio`` (the
capstan ratios ``Eta``). Link masses and centres of mass are kept as parameters (each centre
in its own body frame, as in the source): the mass model behind ``gravity_torque``
(``kinematics.gravity``); the kinematics does not use them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .angles import wrap_into
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo, joint_side, memoised
from .bodies import Body, check_body, columns
from .validation import (
    as_points,
    choice,
    finite_angles,
    nonnegative_vector,
    optional_positive_vector,
    positive_finite,
    positive_vector,
)

ACTUATORS = ("q1", "q2", "q3")
BASE_BRANCHES = ("nearest", "front", "back")
#: Rigid bodies of the source's dynamic model: a = second link, be = first link (with its
#: drum), c = parallelogram follower, df = the q3 drive drum and crank, g = base turret.
BODIES = ("a", "c", "be", "df", "g")
#: ``peak_rating`` / ``mass_model``: the source gives the numbers, or the device has none.
GIVEN = ("given", "none")
#: ``mass_model``: the body data are the device's (``"given"``), estimated from its dimensions and
#: materials (``"estimated"``, marked so in the preset), or the device has none (``"none"``).
MASS_MODELS = ("given", "estimated", "none")
_XYZ = ("x", "y", "z")
#: Labels of an ``inertia_*`` tensor: ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` about the centre of mass, body axes.
TENSOR = ("xx", "yy", "zz", "xy", "xz", "yz")
_DEG = math.pi / 180.0


def _finite_vector(name: str, values: Any, labels: tuple[str, ...], unit: str) -> tuple[float, ...]:
    """``values`` as a tuple of finite floats, one per label, or a ValueError naming ``name``."""
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) != len(labels):
        raise ValueError(f"{name} needs {len(labels)} values ({', '.join(labels)}) in {unit}, got {values!r}")
    out = []
    for label, v in zip(labels, values):
        try:
            number = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"{name}[{label}] must be a finite number in {unit}, got {v!r}") from None
        if not math.isfinite(number):
            raise ValueError(f"{name}[{label}] must be a finite number in {unit}, got {v!r}")
        out.append(number)
    return tuple(out)


@dataclass(frozen=True, slots=True)
class SerialRRRParams:
    """Geometry (m), actuators, limits (rad) and link inertia of a PHANToM-type arm.

    Defaults: PHANToM Premium 1.5 as modelled in ``mahilab/Phantom`` ``cpp/src/PhantomModel.hpp``
    (lines 12-16 masses, 26-30 centres of mass, 33-35 lengths, 38-41 limits, 50 ``Eta``,
    53 and 56 motor nominal and maximum torque, Maxon RE 25 118743).
    """

    link1_length: float = 0.209550
    link2_length: float = 0.169545
    crank_length: float = 0.031750
    motor_torques: tuple[float, float, float] = (0.0286, 0.0286, 0.0286)
    peak_motor_torques: tuple[float, float, float] = (0.129, 0.129, 0.129)
    gear_ratios: tuple[float, float, float] = (13.3, 11.2, 11.2)
    #: Each motor's largest (no-load) speed, motor side, rad/s (``joint_speed_limits`` divides it by
    #: ``gear_ratios``); ``None``: the speeds are not given (no velocity polytope).
    motor_speeds: tuple[float, ...] | None = None
    lower_limits: tuple[float, float, float] = (-90 * _DEG, -124 * _DEG, -29 * _DEG)
    upper_limits: tuple[float, float, float] = (90 * _DEG, 119 * _DEG, 214 * _DEG)
    max_q2_minus_q3: float = 65 * _DEG
    max_q3_minus_q2: float = 55 * _DEG
    link_masses: tuple[float, ...] = (0.026220, 0.026146, 0.267840, 0.215420, 0.361590)
    com_a: tuple[float, float, float] = (0.00002423, -0.05237892, 0.0)
    com_c: tuple[float, float, float] = (0.0, 0.10477739, 0.0)
    com_be: tuple[float, float, float] = (-0.03518875, -0.0000628, 0.00232416)
    com_df: tuple[float, float, float] = (-0.05153541, 0.00060903, 0.00402873)
    com_g: tuple[float, float, float] = (-0.01048563, 0.01396387, -0.05380827)
    #: Inertia tensors about each centre of mass, body axes, ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` as
    #: tensor entries, kg m^2: ``PhantomModel.hpp:19-23`` ``Ic_*`` stores xx, xy, xz, yy, yz, zz with
    #: the products of inertia positive, and ``matlab/dynamics.m`` puts ``-xy, -xz, -yz`` in the tensor.
    inertia_a: tuple[float, ...] = (6.029e-05, 5.7e-07, 6.004e-05, 0.0, 0.0, 0.0)
    inertia_c: tuple[float, ...] = (0.00013177, 8.9e-07, 0.00013138, 0.0, 0.0, 0.0)
    inertia_be: tuple[float, ...] = (0.0001133, 0.00091667, 0.00082222, -4.1e-07, 2.296e-05, -4.8e-07)
    inertia_df: tuple[float, ...] = (0.0001214, 0.00026133, 0.00015823, 3.2e-07, 7.45e-06, -3.23e-06)
    inertia_g: tuple[float, ...] = (0.0015202, 0.0012112, 0.00093887, -5.838e-05, -0.00018147, -0.00023832)
    #: Each motor's rotor inertia, motor side, kg m^2 (``PhantomModel.hpp:65`` ``J_mot``, Maxon RE 25).
    rotor_inertias: tuple[float, float, float] = (1.08e-06, 1.08e-06, 1.08e-06)
    base_branch: str = "nearest"
    #: Whether ``peak_motor_torques`` is the device's (``"given"``) or it has no peak rating (``"none"``:
    #: ``peak_torque_limits`` is None, and ``--rating peak`` is refused).
    peak_rating: str = "given"
    #: Whether ``link_masses``, ``com_*``, ``inertia_*`` and ``rotor_inertias`` are the device's
    #: (``"given"``), estimated (``"estimated"``), or it has no mass model (``"none"``: gravity and
    #: masses are refused rather than computed from another device's bodies).
    mass_model: str = "given"
    #: One sensor count of each joint, joint side (rad), and whether it is the device's
    #: (``joint_sensors = "given"``) or its sensors are not modelled (``"none"``: no resolution).
    joint_resolution: tuple[float, float, float] = (360.0 / (4096 * 13.3) * _DEG, 360.0 / (4096 * 11.2) * _DEG,
                                                    360.0 / (4096 * 11.2) * _DEG)
    joint_sensors: str = "given"

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("link1_length", "link2_length", "crank_length"):
            set_(self, name, positive_finite(name, getattr(self, name), "m"))
        for name in ("max_q2_minus_q3", "max_q3_minus_q2"):
            value = positive_finite(name, getattr(self, name), "rad")
            if not value < math.pi / 2:
                raise ValueError(f"{name} must be below 90 deg (pi/2 rad): the elbow would straighten or fold "
                                 f"flat (a singularity), got {value} rad")
            set_(self, name, value)
        for name in ("motor_torques", "peak_motor_torques"):
            set_(self, name, positive_vector(name, getattr(self, name), ACTUATORS, "N m"))
        set_(self, "gear_ratios", positive_vector("gear_ratios", self.gear_ratios, ACTUATORS))
        set_(self, "motor_speeds", optional_positive_vector("motor_speeds", self.motor_speeds, ACTUATORS, "rad/s"))
        set_(self, "lower_limits", finite_angles("lower_limits", self.lower_limits, ACTUATORS))
        set_(self, "upper_limits", finite_angles("upper_limits", self.upper_limits, ACTUATORS))
        for label, lo, hi in zip(ACTUATORS, self.lower_limits, self.upper_limits):
            if not lo < hi:
                raise ValueError(f"lower_limits[{label}] must be below upper_limits[{label}], got {lo} >= {hi}")
        set_(self, "link_masses", positive_vector("link_masses", self.link_masses, BODIES, "kg"))
        for body in BODIES:
            name = f"com_{body}"
            set_(self, name, _finite_vector(name, getattr(self, name), _XYZ, "m"))
        for body in BODIES:
            name = f"inertia_{body}"
            check_body(body, 1.0, (0.0, 0.0, 0.0), getattr(self, name), key=name)
        set_(self, "rotor_inertias", nonnegative_vector("rotor_inertias", self.rotor_inertias, ACTUATORS, "kg m^2"))
        choice("base_branch", self.base_branch, BASE_BRANCHES)
        choice("peak_rating", self.peak_rating, GIVEN)
        choice("mass_model", self.mass_model, MASS_MODELS)
        set_(self, "joint_resolution", positive_vector("joint_resolution", self.joint_resolution, ACTUATORS, "rad"))
        choice("joint_sensors", self.joint_sensors, GIVEN)


class SerialRRR(MechanismBase):
    """PHANToM-type arm: base yaw, shoulder, parallelogram-driven absolute ``q3``; ``q = (q1, q2, q3)``."""

    n_joints = 3
    task_dim = 3
    joint_names = ACTUATORS
    task_names = ("x", "y", "z")
    PARAM_INFO = (
        ParamInfo("link1_length", "mm", 1e-3, "First link l1, shoulder to elbow"),
        ParamInfo("link2_length", "mm", 1e-3, "Second link l2, elbow to tip"),
        ParamInfo("crank_length", "mm", 1e-3, "Parallelogram drive crank l3 (drawing and gravity only)"),
        ParamInfo("motor_torques", "N m", 1.0, "Continuous (nominal) motor torque", ACTUATORS),
        ParamInfo("peak_motor_torques", "N m", 1.0, "Peak (stall) motor torque", ACTUATORS),
        ParamInfo("gear_ratios", "", 1.0, "Capstan ratio, joint / motor", ACTUATORS),
        ParamInfo("lower_limits", "deg", _DEG, "Lower joint limit", ACTUATORS),
        ParamInfo("upper_limits", "deg", _DEG, "Upper joint limit", ACTUATORS),
        ParamInfo("max_q2_minus_q3", "deg", _DEG, "Coupling limit: largest q2 - q3"),
        ParamInfo("max_q3_minus_q2", "deg", _DEG, "Coupling limit: largest q3 - q2"),
        ParamInfo("link_masses", "kg", 1.0, "Body masses (a: link 2, c: follower, be: link 1, df: q3 drum, "
                  "g: turret)", BODIES),
        ParamInfo("rotor_inertias", "g cm^2", 1e-7, "Motor rotor inertia (motor side; felt at the joint "
                  "times the gear ratio squared)", ACTUATORS),
        ParamInfo("base_branch", "", 1.0, "IK branch of the base joint", choices=BASE_BRANCHES),
        ParamInfo("peak_rating", "", 1.0, "peak_motor_torques are the device's (given) or it has no peak rating",
                  choices=GIVEN),
        ParamInfo("mass_model", "", 1.0, "Body data are the device's (given), estimated, or it has no mass "
                  "model (none)", choices=MASS_MODELS),
        ParamInfo("joint_resolution", "deg", _DEG, "One encoder count of the joint (joint side)", ACTUATORS),
        ParamInfo("joint_sensors", "", 1.0, "joint_resolution is the device's (given) or not modelled (none)",
                  choices=GIVEN),
    )

    #: Parameters a preset may set that are not sliders: each body's centre of mass ``com_*`` (signed,
    #: in its body frame) and inertia tensor ``inertia_*``. The app's parameter rows (built from
    #: PARAM_INFO) take positive lengths only; ``resources.schema`` reads and writes these rows too.
    #: Their defaults are the PHANToM Premium's (the source's values).
    PRESET_PARAMS = (
        *(ParamInfo(f"com_{body}", "mm", 1e-3, f"Centre of mass of body {body}, in its body frame", _XYZ)
          for body in BODIES),
        *(ParamInfo(f"inertia_{body}", "g cm^2", 1e-7, f"Inertia tensor of body {body} about its centre of "
                    "mass, body axes (tensor entries)", TENSOR) for body in BODIES),
    )
    singularity_classes = ("none", "inverse")

    def __init__(self, params: SerialRRRParams | None = None, **kwargs) -> None:
        super().__init__(params if params is not None else SerialRRRParams(**kwargs))

    @property
    def singular_tolerance(self) -> float:
        """Dimensionless bound below which ``r / (l1 + l2)`` or ``cos(q2 - q3)`` counts as zero: ``8 eps``.

        ``r = l1 cos q2 + l2 sin q3`` is a sum of two rounded products, each within ``2 eps`` of
        its link length, so a true zero comes out below ``4 eps (l1 + l2)``; the factor 2 is margin.

        Returns
        -------
        float
        """
        return 8 * float(np.finfo(float).eps)

    def _radial_and_elbow(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Scaled radial distance ``r / (l1 + l2)`` and ``cos(q2 - q3)``, shapes (...)."""
        l1, l2 = self.params.link1_length, self.params.link2_length
        with np.errstate(invalid="ignore"):
            r = (l1 * np.cos(q[..., 1]) + l2 * np.sin(q[..., 2])) / (l1 + l2)
            return r, np.cos(q[..., 1] - q[..., 2])

    def singular_legs(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Which actuators' Jacobian column vanishes, bool (..., 3): ``q1`` on the base axis (``r = 0``)."""
        q = as_points("q", q, 3)
        r, _ = self._radial_and_elbow(q)
        legs = np.zeros(q.shape, bool)
        legs[..., 0] = np.abs(r) <= self.singular_tolerance
        return legs

    def singularity(self, q: ArrayLike, x: ArrayLike | None = None) -> NDArray[np.int8]:
        """1 (``"inverse"``) where ``det J = l1 l2 r cos(q2 - q3)`` vanishes, else 0; int8 (...).

        On the base axis (``r = 0``) the base joint has no lever; with the elbow straight or
        folded (``cos(q2 - q3) = 0``, outside the coupling limits) links 1 and 2 move alike.
        """
        q = as_points("q", q, 3)
        r, c = self._radial_and_elbow(q)
        tol = self.singular_tolerance
        return ((np.abs(r) <= tol) | (np.abs(c) <= tol)).astype(np.int8)

    def singular_loci(self, samples: int = 721) -> dict[str, FloatArray]:
        """Points just off the base axis, ``(+-1e-9 (l1 + l2), 0, z)``, for ``metrics.suprema``; (2 samples, 3).

        The base axis is the only singular locus the coupling limits leave (they keep
        ``|q2 - q3|`` below 90 deg). ``z`` runs over ``[-(l1 + l2), l1 + l2]``; the caller keeps
        the feasible points inside its domain.

        Examples
        --------
        >>> SerialRRR().singular_loci(samples=5)["inverse"].shape
        (10, 3)
        """
        reach = self.params.link1_length + self.params.link2_length
        z = np.linspace(-reach, reach, samples)
        off = np.full(samples, 1e-9 * reach)
        zero = np.zeros(samples)
        pts = np.concatenate([np.stack([off, zero, z], -1), np.stack([-off, zero, z], -1)])
        return {"inverse": pts}

    def home_pose(self) -> FloatArray:
        """The source's nominal pose ``q = 0`` (link 1 horizontal, link 2 down): ``(l1, 0, -l2)``, (3,), m.

        Returns
        -------
        ndarray, shape (3,)

        Examples
        --------
        >>> SerialRRR().home_pose().tolist()
        [0.20955, 0.0, -0.169545]
        """
        return np.array([self.params.link1_length, 0.0, -self.params.link2_length])

    def peak_torque_limits(self) -> FloatArray | None:
        """Joint-side peak torque of each actuator, ``peak_motor_torque_u * gear_ratio_u``, shape (3,).

        None where the device has no peak rating (``peak_rating = "none"``).

        Examples
        --------
        >>> SerialRRR().peak_torque_limits().round(4).tolist()
        [1.7157, 1.4448, 1.4448]
        >>> SerialRRR(peak_rating="none").peak_torque_limits() is None
        True
        """
        if self.params.peak_rating == "none":
            return None
        return joint_side(self.params.peak_motor_torques, self.params.gear_ratios)

    # -- mass model (kinematics.gravity) ---------------------------------------------------
    @property
    def has_mass_model(self) -> bool:
        """Whether the body data are given or estimated (``mass_model`` not ``"none"``): gravity and masses."""
        return self.params.mass_model != "none"

    def body_masses(self) -> FloatArray:
        """Masses of the bodies ``BODIES`` (a, c, be, df, g), shape (5,), kg (``link_masses``).

        Examples
        --------
        >>> SerialRRR().body_masses().tolist()
        [0.02622, 0.026146, 0.26784, 0.21542, 0.36159]
        """
        return np.asarray(self.params.link_masses, float)

    def _body_coordinates(self, q: FloatArray):
        """Each centre of mass in the arm's turning frame, and its derivatives in q2 and q3.

        In the frame of unit vectors ``r = (cos q1, sin q1, 0)`` (radial), ``t = (-sin q1, cos q1, 0)``
        and ``k = (0, 0, 1)``, a centre is ``rad r + tan t + h k``. The body frames are those
        of the source's dynamic model (``PhantomModel.cpp`` ``U``, ``K``; its potential ``U``
        fixes each axis' height): link 1 ``be`` turns by q2 (x along link 1), link 2 ``a`` by
        q3 about the elbow (-y along link 2), the drive drum and crank ``df`` by q3 (x along the
        crank, which the parallelogram keeps parallel to link 2), the follower ``c`` by q2 at
        the crank's end (y along the follower, parallel to link 1); every z axis is ``-t``
        (the shoulder axis). The turret ``g`` turns with q1 only; its frame is taken as frame
        {0} turned by q1 (the source's ``U`` and ``K`` fix only its height and radius).

        Returns ``rad, tan, h`` (..., 5) and ``d_rad, d_h`` (..., 5, 2): derivatives in (q2, q3).
        """
        p = self.params
        l1, l3 = p.link1_length, p.crank_length
        s2, c2 = np.sin(q[..., 1])[..., None], np.cos(q[..., 1])[..., None]
        s3, c3 = np.sin(q[..., 2])[..., None], np.cos(q[..., 2])[..., None]
        com = np.array([p.com_a, p.com_c, p.com_be, p.com_df, p.com_g])      # (5, 3), BODIES order
        x, y, z = com[:, 0], com[:, 1], com[:, 2]
        zero = np.zeros(q.shape[:-1] + (1,))
        # Rows of (a, c, be, df, g); each entry broadcasts over the batch, shape (..., 1).
        rad = [l1 * c2 + x[0] * c3 - y[0] * s3, l3 * s3 + x[1] * s2 + y[1] * c2, x[2] * c2 - y[2] * s2,
               x[3] * s3 + y[3] * c3, zero + x[4]]
        h = [l1 * s2 + x[0] * s3 + y[0] * c3, -l3 * c3 - x[1] * c2 + y[1] * s2, x[2] * s2 + y[2] * c2,
             -x[3] * c3 + y[3] * s3, zero + z[4]]
        tan = [zero - z[0], zero - z[1], zero - z[2], zero - z[3], zero + y[4]]
        d_rad = [(-l1 * s2, -x[0] * s3 - y[0] * c3), (x[1] * c2 - y[1] * s2, l3 * c3),
                 (-x[2] * s2 - y[2] * c2, zero), (zero, x[3] * c3 - y[3] * s3), (zero, zero)]
        d_h = [(l1 * c2, x[0] * c3 - y[0] * s3), (x[1] * s2 + y[1] * c2, l3 * s3),
               (x[2] * c2 - y[2] * s2, zero), (zero, x[3] * s3 + y[3] * c3), (zero, zero)]

        def stack(rows):
            return np.concatenate(rows, axis=-1)

        def stack2(rows):
            return np.stack([np.concatenate([r[k] for r in rows], axis=-1) for k in (0, 1)], axis=-1)

        return stack(rad), stack(tan), stack(h), stack2(d_rad), stack2(d_h)

    @memoised
    def bodies(self) -> tuple[Body, ...]:
        """The source's five bodies ``BODIES``: ``link_masses``, ``com_*`` and ``inertia_*``."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        p = self.params
        return tuple(Body(name, mass, getattr(p, f"com_{name}"), getattr(p, f"inertia_{name}"))
                     for name, mass in zip(BODIES, p.link_masses))

    def body_poses(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Body frames of ``BODIES`` in frame {0} (the frames ``_body_coordinates`` describes).

        In the turning frame ``(r, t, k)`` each of link 1 (be), link 2 (a), the drum (df) and
        the follower (c) has its z axis along ``-t`` and turns in the r-k plane by q2 or q3;
        the turret (g) is the turning frame itself.

        Returns
        -------
        rotations : ndarray, shape (..., 5, 3, 3)
        origins : ndarray, shape (..., 5, 3), m
        """
        q = as_points("q", q, 3)
        p = self.params
        c1, s1 = np.cos(q[..., 0]), np.sin(q[..., 0])
        s2, c2, s3, c3 = np.sin(q[..., 1]), np.cos(q[..., 1]), np.sin(q[..., 2]), np.cos(q[..., 2])
        zero, one = np.zeros_like(c1), np.ones_like(c1)
        turning = np.stack([np.stack([c1, s1, zero], -1), np.stack([-s1, c1, zero], -1),
                            np.stack([zero, zero, one], -1)], axis=-1)                  # columns r, t, k

        def plane(x_axis, y_axis):
            """Body axes (columns) in the turning frame: x and y in the r-k plane, z = -t."""
            xr, xk = x_axis
            yr, yk = y_axis
            return np.stack([np.stack([xr, zero, xk], -1), np.stack([yr, zero, yk], -1),
                             np.stack([zero, -one, zero], -1)], axis=-1)

        local = np.stack([plane((c3, s3), (-s3, c3)),            # a: link 2, turning by q3 at the elbow
                          plane((s2, -c2), (c2, s2)),            # c: follower, parallel to link 1
                          plane((c2, s2), (-s2, c2)),            # be: link 1
                          plane((s3, -c3), (c3, s3)),            # df: drum and crank
                          np.broadcast_to(np.eye(3), c1.shape + (3, 3))], axis=-3)      # g: turret
        l1, l3 = p.link1_length, p.crank_length
        origins_local = np.stack([np.stack([l1 * c2, zero, l1 * s2], -1), np.stack([l3 * s3, zero, -l3 * c3], -1),
                                  np.stack([zero, zero, zero], -1), np.stack([zero, zero, zero], -1),
                                  np.stack([zero, zero, zero], -1)], axis=-2)           # (..., 5, 3)
        rotations = turning[..., None, :, :] @ local
        origins = (turning[..., None, :, :] @ origins_local[..., None])[..., 0]
        return rotations, origins

    def body_velocities(self, q: ArrayLike, x: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, None]:
        """Exact ``dc_b/dq``, ``dw_b/dq`` (5, 3, 3, N), ``R_b`` (5, 3, 3, N) and ``None`` (joint coordinates).

        Component-first (``kinematics.bodies``), the batch flattened last. Every body turns with
        the turret about ``k`` at ``q1dot``; in the r-k plane link 1 (be) and the follower (c)
        turn at ``q2dot`` and link 2 (a) and the drum (df) at ``q3dot`` about their z axis ``-t``
        (the parallelogram keeps each at its own joint's rate). A centre ``rad r + tan t + h k``
        moves at ``rad t - tan r`` per unit ``q1`` and ``d_rad r + d_h k`` per unit ``q2``, ``q3``.
        """
        q = as_points("q", q, 3).reshape(-1, 3)
        rad, tan, h, d_rad, d_h = (columns(a) for a in self._body_coordinates(q))        # (5, N), (5, 2, N)
        c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
        s2, c2, s3, c3 = np.sin(q[:, 1]), np.cos(q[:, 1]), np.sin(q[:, 2]), np.cos(q[:, 2])
        zero, one = np.zeros_like(c1), np.ones_like(c1)
        r, t, k = np.stack([c1, s1, zero]), np.stack([-s1, c1, zero]), np.stack([zero, zero, one])
        jv = np.empty((5, 3, 3, len(q)))
        jv[:, :, 0] = rad[:, None] * t - tan[:, None] * r
        jv[:, :, 1:] = d_rad[:, None] * r[:, None] + d_h[:, None] * k[:, None]
        jw = np.zeros((5, 3, 3, len(q)))
        jw[:, :, 0] = k
        jw[1:3, :, 1] = -t                                     # c, be: q2
        jw[0, :, 2] = jw[3, :, 2] = -t                         # a, df: q3
        rot = np.empty((5, 3, 3, len(q)))
        for b, ((xr, xk), (yr, yk)) in enumerate((((c3, s3), (-s3, c3)), ((s2, -c2), (c2, s2)),
                                                  ((c2, s2), (-s2, c2)), ((s3, -c3), (c3, s3)))):
            rot[b, :, 0] = xr * r + xk * k
            rot[b, :, 1] = yr * r + yk * k
            rot[b, :, 2] = -t
        rot[4] = np.stack([r, t, k], axis=1)
        return jv, jw, rot, None

    def centres_of_mass(self, q: ArrayLike) -> FloatArray:
        """Centres of mass of ``BODIES`` in frame {0}, shape (..., 5, 3), m (``com_*`` in body frames).

        Examples
        --------
        >>> SerialRRR().centres_of_mass([0.0, 0.0, 0.0])[2].round(6).tolist()   # link 1 at home
        [-0.035189, -0.002324, -6.3e-05]
        """
        q = as_points("q", q, 3)
        rad, tan, h, _, _ = self._body_coordinates(q)
        c1, s1 = np.cos(q[..., 0])[..., None], np.sin(q[..., 0])[..., None]
        return np.stack([rad * c1 - tan * s1, rad * s1 + tan * c1, h], axis=-1)

    def centres_of_mass_jacobian(self, q: ArrayLike) -> FloatArray:
        """``dp_i/dq`` of each centre of mass, shape (..., 5, 3, 3), m/rad; analytic."""
        q = as_points("q", q, 3)
        rad, tan, _, d_rad, d_h = self._body_coordinates(q)
        c1, s1 = np.cos(q[..., 0])[..., None], np.sin(q[..., 0])[..., None]
        # d/dq1 turns r into t and t into -r; q2 and q3 move the centre within the r-k plane.
        d1 = np.stack([-rad * s1 - tan * c1, rad * c1 - tan * s1, np.zeros_like(rad)], axis=-1)
        c1, s1 = c1[..., None], s1[..., None]
        d23 = np.stack([d_rad * c1, d_rad * s1, d_h], axis=-2)                # (..., 5, 3, 2)
        return np.concatenate([d1[..., None], d23], axis=-1)

    def forward(self, q: ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Tip ``P`` (..., 3) in frame {0}, m, for joints ``q`` (..., 3), and whether it assembles.

        A serial arm assembles for every finite ``q``; limits are ``feasible``'s business.

        Examples
        --------
        >>> x, ok = SerialRRR().forward([0.0, 0.0, 0.0])
        >>> x.round(6).tolist(), bool(ok)
        ([0.20955, 0.0, -0.169545], True)
        """
        q = as_points("q", q, 3)
        l1, l2 = self.params.link1_length, self.params.link2_length
        ok = np.all(np.isfinite(q), axis=-1)
        with np.errstate(invalid="ignore"):          # sin/cos of inf: nan, masked below
            q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
            r = l1 * np.cos(q2) + l2 * np.sin(q3)
            p = np.stack([r * np.cos(q1), r * np.sin(q1), l1 * np.sin(q2) - l2 * np.cos(q3)], axis=-1)
        return np.where(ok[..., None], p, np.nan), ok

    def jacobian(self, q: ArrayLike, x: ArrayLike | None = None) -> FloatArray:
        """``J = dP/dq`` (..., 3, 3) in m/rad (``PhantomModel.cpp`` ``J``), without capstan ratios.

        Examples
        --------
        >>> (SerialRRR().jacobian([0.0, 0.0, 0.0]).round(6) + 0.0).tolist()     # + 0.0: no -0.0
        [[0.0, 0.0, 0.169545], [0.20955, 0.0, 0.0], [0.0, 0.20955, 0.0]]
        """
        q = as_points("q", q, 3)
        l1, l2 = self.params.link1_length, self.params.link2_length
        with np.errstate(invalid="ignore"):
            s1, c1 = np.sin(q[..., 0]), np.cos(q[..., 0])
            s2, c2 = np.sin(q[..., 1]), np.cos(q[..., 1])
            s3, c3 = np.sin(q[..., 2]), np.cos(q[..., 2])
            r = l1 * c2 + l2 * s3
            # On the base axis (``singular_legs``) q1's column is exactly 0, not rounding noise
            # (``base.singular_limit``): the five-bar's rule, so every metric takes its limit.
            r = np.where(np.abs(r) <= self.singular_tolerance * (l1 + l2), 0.0, r)
            jac = np.empty((3, 3) + q.shape[:-1])
            jac[0, 0], jac[0, 1], jac[0, 2] = -s1 * r, -l1 * c1 * s2, l2 * c1 * c3
            jac[1, 0], jac[1, 1], jac[1, 2] = c1 * r, -l1 * s1 * s2, l2 * s1 * c3
            jac[2, 0], jac[2, 1], jac[2, 2] = 0.0, l1 * c2, l2 * s3
        return np.moveaxis(jac, (0, 1), (-2, -1))

    def inverse(self, x: ArrayLike, base_branch: str | None = None) -> tuple[FloatArray, BoolArray]:
        """Joint angles ``q`` (..., 3) reaching ``x`` (..., 3) in frame {0}, m, and ``reachable`` (...).

        The base joint reaches a point from the front (signed radial coordinate ``s = +rho``,
        ``q1 = atan2(y, x)``) or from over the top (``s = -rho``, ``q1 = atan2(y, x) - pi``,
        the source's solution ``Q_b``); ``"nearest"`` takes the one with the smaller ``|q1|``, so
        the slice ``y = 0`` is swept at ``q1 = 0``. The elbow branch is the one the coupling
        limits allow (``0 < q3 - q2 + pi/2 < pi``, elbow above the line shoulder-tip):
        ``q2 = atan2(z, s) + alpha``, ``q3 = q2 + beta - pi/2`` with ``alpha`` the angle at the
        shoulder and ``beta`` the interior angle at the elbow of the triangle shoulder-elbow-tip
        (the source's ``inverse_kinematics``). Unreachable points get ``nan``; limits are
        checked by ``feasible``.

        Examples
        --------
        >>> mech = SerialRRR()
        >>> q, ok = mech.inverse(mech.forward([0.3, 0.2, 0.4])[0])
        >>> bool(np.allclose(q, [0.3, 0.2, 0.4], rtol=0.0, atol=1e-12)), bool(ok)
        (True, True)
        """
        branch = choice("base_branch", base_branch or self.params.base_branch, BASE_BRANCHES)
        x = as_points("x", x, 3)
        l1, l2 = self.params.link1_length, self.params.link2_length
        with np.errstate(invalid="ignore", divide="ignore"):
            px, py, pz = x[..., 0], x[..., 1], x[..., 2]
            rho = np.hypot(px, py)
            azimuth = np.arctan2(py, px)
            over = _wrap_pi(azimuth - np.pi)
            if branch == "front":
                back = np.zeros(rho.shape, bool)
            elif branch == "back":
                back = np.ones(rho.shape, bool)
            else:
                back = np.abs(over) < np.abs(azimuth)
            q1 = np.where(back, over, azimuth)
            s = np.where(back, -rho, rho)
            d_sq = s * s + pz * pz
            d = np.sqrt(d_sq)
            cos_alpha = (l1 * l1 + d_sq - l2 * l2) / (2.0 * l1 * d)
            cos_beta = (l1 * l1 + l2 * l2 - d_sq) / (2.0 * l1 * l2)
            slack = 8 * np.finfo(float).eps
            ok = np.all(np.isfinite(x), axis=-1) & (d > 0.0)
            ok &= (np.abs(cos_alpha) <= 1.0 + slack) & (np.abs(cos_beta) <= 1.0 + slack)
            q2 = np.arctan2(pz, s) + np.arccos(np.clip(cos_alpha, -1.0, 1.0))
            q3 = q2 + np.arccos(np.clip(cos_beta, -1.0, 1.0)) - 0.5 * np.pi
            # atan2 gives q2 in (-pi, 2pi): shift q2 and q3 together (keeping q3 - q2) by the
            # multiple of 2 pi that puts q2 at or above its lower limit.
            q2_wrapped, _ = wrap_into(q2, self.params.lower_limits[1], self.params.upper_limits[1])
            q3 = q3 + (q2_wrapped - q2)
            q = np.stack([q1, q2_wrapped, q3], axis=-1)
        return np.where(ok[..., None], q, np.nan), ok

    def feasible(self, q: ArrayLike, x: ArrayLike | None = None) -> BoolArray:
        """Joint limits and the parallelogram's coupling limits (``PhantomModel.cpp`` ``validate_angles``).

        Examples
        --------
        >>> SerialRRR().feasible([[0.0, 0.0, 0.0], [0.0, 1.2, 0.0]]).tolist()
        [True, False]
        """
        q = as_points("q", q, 3)
        p = self.params
        with np.errstate(invalid="ignore"):
            ok = np.all(np.isfinite(q), axis=-1)
            for i in range(3):
                ok &= (q[..., i] >= p.lower_limits[i]) & (q[..., i] <= p.upper_limits[i])
            ok &= q[..., 1] - q[..., 2] <= p.max_q2_minus_q3
            ok &= q[..., 2] - q[..., 1] <= p.max_q3_minus_q2
        return ok

    def link_points(self, q: ArrayLike) -> FloatArray:
        """Polyline tip -> elbow -> shoulder -> crank end -> follower joint on link 2, (..., 5, 3).

        Together the edges draw link 2, link 1, the drive crank and the parallelogram's
        follower (parallel to link 1, meeting link 2 ``crank_length`` below the elbow).
        """
        q = as_points("q", q, 3)
        p = self.params
        q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
        cos1, sin1 = np.cos(q1), np.sin(q1)

        def point(s, w):
            return np.stack([s * cos1, s * sin1, w], axis=-1)

        d1 = (np.cos(q2), np.sin(q2))
        d2 = (np.sin(q3), -np.cos(q3))
        l1, l2, l3 = p.link1_length, p.link2_length, p.crank_length
        zero = np.zeros_like(q1)
        shoulder = point(zero, zero)
        elbow = point(l1 * d1[0], l1 * d1[1])
        tip = point(l1 * d1[0] + l2 * d2[0], l1 * d1[1] + l2 * d2[1])
        crank = point(l3 * d2[0], l3 * d2[1])
        follower = point(l1 * d1[0] + l3 * d2[0], l1 * d1[1] + l3 * d2[1])
        return np.stack([tip, elbow, shoulder, crank, follower], axis=-2)


def _wrap_pi(angle: FloatArray) -> FloatArray:
    """Angle wrapped into [-pi, pi)."""
    return angle - 2.0 * np.pi * np.floor((angle + np.pi) / (2.0 * np.pi))
