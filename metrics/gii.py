"""Global Isotropy Index with actuator and task scaling (paper 001, eqs. 11-13 and 23-27).

The sensor (velocity) GII of eqs. 23-27 is in ``metrics.sensor_gii``; it shares this module's
scaling core, ``GIIResult`` and its reduction.

The index
---------
Paper 001 (Stocco, Salcudean, Sassani) rates a design ``p`` by

.. math::

    GII(p) = \\frac{\\min_{x \\in W} \\sigma_{min}(S_J J(p, x) S_T^{-1})}
                  {\\max_{x \\in W} \\sigma_{max}(S_J J(p, x) S_T^{-1})}        (11)

    S_J = diag(tau_1, ..., tau_n) / tau_1                                     (12)
    S_T = diag(F_i, F_j, F_k, M_i, M_j, M_k) / F_i                            (13)

with ``tau_u`` the actuators' torque capabilities and ``F, M`` the forces and moments the
task requires. Eq. (11) is written as a minimum over pairs ``(x0, x1)`` of
``sigma_min(x0) / sigma_max(x1)``, which is the ratio of the two separate extremes above.

Which Jacobian is scaled
------------------------
The paper's statics read ``f = J^T tau`` (its eq. 22) and its kinematics ``qdot = J xdot``
(eq. 23): *its* ``J`` (n x m) maps task velocity to joint rates. Ours maps joint rates to
task velocity, ``xdot = J qdot`` (m x n), with ``tau = J^T f``. So, for a square,
non-singular mechanism::

    paper J    = our J^-1            (n x m, rows are actuators)
    paper J^T  = our J^-T = A        (m x n, the force map f = A tau; ``generators`` in
                                      metrics.zonotopes)

Dimensional consistency settles it independently of the shapes (our ``J^T`` is also n x m,
but scaling it as ``S_J J^T S_T^-1`` gives entries ``tau_u J_au / F_a`` in m^2 for a
revolute actuator and a translational row: not dimensionless, so not what eq. 11 means).
With ``A = J^-T`` the entries of ``diag(tau) A^T diag(F)^-1`` are
``tau_u dq_u/dx_a / F_a``: (N m)(rad/m)/N, dimensionless. Written on the task side,

    S_T^-1 A S_J = (F_i / tau_1) * diag(F)^-1 A diag(tau)

maps torques normalised by their limits to forces normalised by the requirements; it is
the transpose of the paper's ``S_J J S_T^-1``, so its singular values are the paper's.

Two equivalent inputs (``kind``)
--------------------------------
``kind="jacobian"`` (default) takes our ``J`` and scales ``M = S_T J S_J^-1``.
``kind="force_map"`` takes ``A`` (f = A tau) and scales ``M = S_T^-1 A S_J``.

For square ``J`` the two matrices are inverse transposes of each other
(``(S_T^-1 J^-T S_J)^-T = S_T J S_J^-1``), so their singular values are reciprocals, and
the GII is the *same* number either way: with ``s(x) = 1/sigma(x)``,
``min_x s_min / max_x s_max = (1/max_x sigma_max) / (1/min_x sigma_min)``. The extremes
swap places, which ``GIIResult.weakest`` / ``strongest`` resolve. Evaluating on our ``J``
needs no inverse and stays finite at the five-bar's inverse (boundary) singularities.
Physically the scaled singular values are the semi-axes of the normalised force ellipsoid
(the image of the unit ball of normalised torques): ``sigma(M_force)`` directly,
``1/sigma(M_jacobian)`` for our ``J``; the local isotropy ``sigma_min / sigma_max`` is the
ratio of its shortest to its longest semi-axis under either kind.

Non-square matrices: the task needs all ``m`` directions, so ``sigma_min`` is the m-th
singular value. With redundant actuation (force map m x n, n > m: the Twin-Pantograph's
redundant waist actuator) or a kinematically redundant serial arm (our ``J``, n > m) that is
the smallest of the ``m`` values. With fewer actuators than task directions (n < m) the
m-th value is 0 and the isotropy is 0: ``scaled_singular_values`` pads with zeros. For a
redundantly actuated mechanism only ``kind="force_map"`` is the paper's index; the
reciprocity above needs a square matrix.

Units (SI)
----------
After the normalisation by ``tau_1`` and ``F_i``, ``S_J`` is dimensionless (for actuators of
one kind) and the force entries of ``S_T`` are too, but a moment over a force is a length:
paper 001's Table I (pencil grip, relative to ``F_i``) is forces 1.0, 1.0, 1.5 and moments
3.6 cm, 0.5 cm, 3.9 cm, and its eq. 19 writes them as 3.6, 0.5, 3.9 because its Jacobians
are in cm. With SI Jacobians (m, rad) they must be 0.036, 0.005, 0.039 m:
``HUMAN_HAND_S_T``. Every entry of ``M`` then has one unit, ``F_i / tau_1`` for a force map
and ``tau_1 / F_i`` for our ``J`` (1/m and m for revolute actuators), so its singular values
compare like with like. Using 3.6 with an SI
Jacobian weighs moments 100 times too heavily and changes the GII.
The paper expresses ``J`` in the end-effector frame before scaling, because Table I is
relative to the hand: ``rotate_task_rows`` does that for rows ``(v, omega)``.
In Table I's frame ``j`` is the pen axis (smallest moment, 0.5 cm: roll).

Properties (tested)
-------------------
* Multiplying all of ``S_J`` or all of ``S_T`` by a constant (e.g. all torques by ``c``)
  leaves the GII unchanged; the normalisation by ``tau_1`` and ``F_i`` makes the scaled
  values themselves unchanged as well.
* The GII depends on the workspace as a set: reordering samples changes neither value nor,
  without ties, the location of the extremes (ties go to the first sample in C order).
* ``GII <= min_x sigma_min(x) / sigma_max(x) <= 1``: for every x,
  ``min sigma_min <= sigma_min(x)`` and ``max sigma_max >= sigma_max(x)``. Equality holds
  iff one sample attains both extremes (e.g. a one-sample workspace).

Bad samples
-----------
Infeasible samples (``feasible`` False) are left out and not computed; with none feasible
the GII is ``nan``. A matrix with a non-finite entry (our five-bar's ``J`` at a direct
singularity) is singular: ``metrics.linalg`` gives it ``inf`` singular values, and the GII
of a workspace with an infinite ``sigma_max`` (or an all-zero matrix) is 0.

================================  ==========================================================
function                          returns
================================  ==========================================================
``actuator_scale``                eq. 12: ``t / t_1``, shape (..., n)
``task_scale``                    eq. 13: ``(F, M) / F_i``, shape (..., m)
``scaled_matrix``                 ``S_T J S_J^-1`` or ``S_T^-1 A S_J``, shape (..., m, n)
``scaled_singular_values``        its m singular values, descending, shape (..., m)
``local_isotropy``                ``sigma_min / sigma_max``, shape (...)
``gii``                           eq. 11 over all batch axes, a ``GIIResult``
``gii_from_extremes``             eq. 11 from per-sample ``sigma_min``, ``sigma_max``
``rotate_task_rows``              ``J`` expressed in a rotated (end-effector) frame
``velocity_scaled_matrix``        eq. 23 scaled by eqs. 26-27: ``S_J K S_T``, shape (..., n, m)
``velocity_singular_values``      its m singular values, descending, shape (..., m)
``velocity_gii``                  the sensor (velocity) GII over a workspace, a ``GIIResult``
================================  ==========================================================

The velocity (sensor-resolution) GII, paper 001 eqs. 23-27
-----------------------------------------------------------
Sec. VI re-uses eq. 11 to choose position-sensor resolutions: the matrix is the velocity map
of eq. 23, ``qdot = K xdot`` (the paper's ``J``: n x m, rows are actuators; ours is
``K = A^T``, the transpose of ``force_map``, by virtual work ``tau . qdot = w . xi``; for a
square mechanism ``K = J^-1``), ``S_J`` holds the joints' sensor resolutions ``R_u`` (eq. 26,
counts per joint radian, normalised by the shoulder's ``R_s``) and ``S_T`` the hand's
velocity capabilities (eq. 27, normalised by ``v_i``).

What we assumed where the text is silent (reconstruction, not the paper's words):

* **S_T multiplies.** The paper's premise is that the required resolution is inversely
  proportional to the joint's maximum velocity, ``R_u ~ 1/qdot_max,u``, so ``R_u qdot_u`` is
  the normalised joint rate; the hand velocity normalised by its capability is
  ``u = diag(v)^-1 xdot``. Hence ``R qdot = diag(R) K diag(v) u``: the matrix is
  ``M = S_J K S_T`` (task side is the *input* here, where in eq. 11 forces are the output
  and ``S_T^-1`` appears). Every entry of ``M`` then has one unit, 1/m (``R_u K_ua`` in
  rad/m on a translation column; ``(rad/rad) (omega/v)`` on a rotation column), so the GII
  does not depend on the length unit. Eq. 11 read literally (``S_J K S_T^-1``) would mix
  rad/m with m and change with the unit; we do not use it.
* **Units of eq. 27.** Its 0.06 is ``30 rad/s / 500 cm/s`` in 1/cm (the paper's Jacobians
  are in cm); in SI it is ``30 / 5 = 6`` 1/m: ``HUMAN_HAND_VELOCITIES`` (5 m/s on every
  translation, 30 rad/s on every rotation: "applied to all directions equally").
* **Which joints Q_1 scales.** The text says ``Q_1 = R_w / R_s`` (waist over shoulder) and
  the conclusion that the waists want about 1.6 times the shoulders' resolution; eq. 26 as
  printed puts ``R_s`` on entries 1 and 4, which are the waists ``q1, q4`` by the paper's
  own numbering. We follow the text: ``Q_1`` on ``q1`` and ``q4`` (a study file names the
  joints, so the other reading is one edit away; since scaling every resolution by one
  factor leaves the GII unchanged, it gives the same GII at ``1/Q_1``).

``M^T = S_T A S_J`` is ``scaled_matrix(A, R, 1/v, kind="force_map")``: the same singular
values, which is how it is computed. For a square mechanism ``sigma(M)`` are the reciprocals
of ``sigma(diag(v)^-1 J diag(R)^-1)`` (``scaled_singular_values(J, R, 1/v)``), so the GII is
the same; with redundant actuation (the Twin-Pantograph's waist ``q4``: K is 6 x 5) only
``K`` gives the paper's index. The singular values of ``M`` are the semi-axes of the
normalised count-rate ellipsoid (the image of the unit ball of normalised hand velocities);
``GIIResult.weakest`` is where its shortest axis is shortest (``kind="velocity_map"``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian, singular_values

Kind = Literal["jacobian", "force_map"]
KINDS: tuple[str, ...] = ("jacobian", "force_map")
#: Kinds a ``GIIResult`` may have: the two above and the sensor GII's ``"velocity_map"``.
RESULT_KINDS: tuple[str, ...] = KINDS + ("velocity_map",)

#: Paper 001 Table I, forces relative to F_i (i, j, k).
HUMAN_HAND_FORCES: tuple[float, float, float] = (1.0, 1.0, 1.5)
#: Paper 001 Table I, moments relative to F_i (i, j, k): 3.6 cm, 0.5 cm, 3.9 cm, in metres.
HUMAN_HAND_MOMENTS: tuple[float, float, float] = (0.036, 0.005, 0.039)
#: ``S_T`` of paper 001 eq. 19 in SI, for task rows (v_i, v_j, v_k, omega_i, omega_j, omega_k).
HUMAN_HAND_S_T: tuple[float, ...] = HUMAN_HAND_FORCES + HUMAN_HAND_MOMENTS
#: Paper 001 sec. VI (from its Fig. 8): the hand's largest speed, 500 cm/s, in m/s.
HUMAN_HAND_SPEED = 5.0
#: Paper 001 sec. VI: the hand's largest angular speed in a +-45 deg workspace, rad/s.
HUMAN_HAND_ANGULAR_SPEED = 30.0
#: ``S_T`` of paper 001 eq. 27 in SI (m/s, rad/s) for task rows (x, y, z, rx, ry, rz): every direction equal.
HUMAN_HAND_VELOCITIES: tuple[float, ...] = (HUMAN_HAND_SPEED,) * 3 + (HUMAN_HAND_ANGULAR_SPEED,) * 3


def _check_kind(kind: str, allowed: tuple[str, ...] = KINDS) -> str:
    if kind not in allowed:
        raise ValueError(f"kind must be one of {', '.join(map(repr, allowed))}, got {kind!r}")
    return kind


def scale_vector(name: str, values: ArrayLike, size: int | None, what: str) -> FloatArray:
    """Positive finite factors (..., size), normalised by their first entry (eqs. 12-13)."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] == 0 or (size is not None and arr.shape[-1] != size):
        want = f"(..., {size})" if size is not None else "(..., k) with k >= 1"
        raise ValueError(f"{name} must have shape {want} to match {what}, got {arr.shape}")
    if not np.all(np.isfinite(arr) & (arr > 0.0)):
        raise ValueError(f"{name} must be positive and finite, got {arr.tolist()}")
    return arr / arr[..., :1]


def actuator_scale(torque_limits: ArrayLike) -> FloatArray:
    """Diagonal of ``S_J`` (paper 001 eq. 12): ``t_u / t_1``, shape (..., n).

    Parameters
    ----------
    torque_limits : array_like, shape (..., n)
        Each actuator's torque (or force) capability, any common unit, positive.

    Returns
    -------
    ndarray, shape (..., n)
        Dimensionless, first entry 1.

    Examples
    --------
    >>> actuator_scale([2.0, 1.0, 4.0]).tolist()
    [1.0, 0.5, 2.0]
    """
    return scale_vector("torque_limits", torque_limits, None, "the actuators")


def task_scale(forces: ArrayLike, moments: ArrayLike = ()) -> FloatArray:
    """Diagonal of ``S_T`` (paper 001 eq. 13): ``(F, M) / F_i``, shape (..., m).

    Parameters
    ----------
    forces : array_like, shape (..., k)
        Required forces in N, ``F_i`` first.
    moments : array_like, shape (..., l), optional
        Required moments in N m; after division by ``F_i`` they are lengths in m.

    Returns
    -------
    ndarray, shape (..., k + l)
        The forces' entries dimensionless (first entry 1), the moments' in m.

    Examples
    --------
    >>> task_scale([2.0, 2.0, 3.0], [0.072]).tolist()
    [1.0, 1.0, 1.5, 0.036]
    """
    f = np.asarray(forces, dtype=np.float64)
    m = np.asarray(moments, dtype=np.float64)
    if f.ndim == 0 or f.shape[-1] == 0:
        raise ValueError(f"forces must have shape (..., k) with k >= 1, got {f.shape}")
    if m.size == 0:
        both = f
    else:
        if m.ndim == 0:
            raise ValueError(f"moments must have shape (..., l), got {m.shape}")
        shape = np.broadcast_shapes(f.shape[:-1], m.shape[:-1])
        both = np.concatenate([np.broadcast_to(f, shape + f.shape[-1:]),
                               np.broadcast_to(m, shape + m.shape[-1:])], axis=-1)
    if not np.all(np.isfinite(both) & (both > 0.0)):
        raise ValueError(f"forces and moments must be positive and finite, got {both.tolist()}")
    return both / both[..., :1]


def scaled_matrix(jac: ArrayLike, s_j: ArrayLike, s_t: ArrayLike, *, kind: Kind = "jacobian") -> FloatArray:
    """The matrix whose singular values eq. 11 uses, shape (..., m, n).

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        ``kind="jacobian"``: our ``J`` (xdot = J qdot). ``kind="force_map"``: ``A`` with
        ``f = A tau`` (the paper's ``J^T``; ``J^-T`` for a square mechanism).
    s_j : array_like, shape (..., n)
        Actuator torque capabilities or their ratios (eq. 12); normalised by the first here.
    s_t : array_like, shape (..., m)
        Task force/moment requirements or their ratios (eq. 13, SI: moments over forces in
        m); normalised by the first here.

    kind : {"jacobian", "force_map"}
        Which matrix ``jac`` is.

    Returns
    -------
    ndarray, shape (..., m, n)
        ``S_T J S_J^-1`` for ``"jacobian"``, ``S_T^-1 A S_J`` for ``"force_map"``.

    Examples
    --------
    >>> scaled_matrix(np.eye(2), (1.0, 2.0), (1.0, 3.0)).tolist()
    [[1.0, 0.0], [0.0, 1.5]]
    """
    _check_kind(kind)
    mat = as_jacobian(jac, "jac")
    m, n = mat.shape[-2:]
    sj = scale_vector("s_j", s_j, n, f"the {n} actuator columns of jac")
    st = scale_vector("s_t", s_t, m, f"the {m} task rows of jac")
    if kind == "jacobian":
        return st[..., :, None] * mat / sj[..., None, :]
    return mat * sj[..., None, :] / st[..., :, None]


def scaled_singular_values(jac: ArrayLike, s_j: ArrayLike, s_t: ArrayLike, *,
                           kind: Kind = "jacobian") -> FloatArray:
    """Singular values of ``scaled_matrix``, descending, shape (..., m).

    There are always ``m`` (task dimension) values: with fewer actuators than task
    directions (n < m) the missing ones are 0. Matrices with a non-finite entry give
    ``inf`` (from ``metrics.linalg.singular_values``). For a square ``J`` the values for
    ``kind="jacobian"`` are the reciprocals of those for ``kind="force_map"`` with
    ``A = J^-T``, in reverse order. Parameters as in ``scaled_matrix``.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Our ``J`` or a force map ``A``, by ``kind``.
    s_j : array_like, shape (..., n)
        Actuator capabilities or ratios (eq. 12).
    s_t : array_like, shape (..., m)
        Task requirements or ratios (eq. 13), SI.
    kind : {"jacobian", "force_map"}
        Which matrix ``jac`` is.

    Returns
    -------
    ndarray, shape (..., m)
        Descending; dimensionless up to the one unit of ``scaled_matrix``.

    Examples
    --------
    >>> J = np.stack([np.eye(2), np.diag([1.0, 4.0])])
    >>> scaled_singular_values(J, (1.0, 1.0), (1.0, 2.0)).round(6).tolist()
    [[2.0, 1.0], [8.0, 1.0]]
    """
    mat = scaled_matrix(jac, s_j, s_t, kind=kind)
    m, n = mat.shape[-2:]
    sv = singular_values(mat)
    if n < m:
        sv = np.concatenate([sv, np.zeros(sv.shape[:-1] + (m - n,))], axis=-1)
    return sv


def _ratio(small: FloatArray, big: FloatArray) -> FloatArray:
    """``small / big``, with 0 where ``big`` is 0 or infinite (a singular matrix)."""
    ok = np.isfinite(big) & (big > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ok, small / np.where(ok, big, 1.0), 0.0)


def local_isotropy(jac: ArrayLike, s_j: ArrayLike, s_t: ArrayLike, *, kind: Kind = "jacobian") -> FloatArray:
    """``sigma_min / sigma_max`` of the scaled matrix at each sample, shape (...), in [0, 1].

    The same for both kinds (for square ``J``); 0 at singular or non-finite matrices.
    Parameters as in ``scaled_matrix``.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Our ``J`` or a force map ``A``, by ``kind``.
    s_j : array_like, shape (..., n)
        Actuator capabilities or ratios (eq. 12).
    s_t : array_like, shape (..., m)
        Task requirements or ratios (eq. 13), SI.
    kind : {"jacobian", "force_map"}
        Which matrix ``jac`` is.

    Returns
    -------
    ndarray, shape (...)
        Dimensionless, in [0, 1].

    Examples
    --------
    >>> J = np.stack([np.eye(2), np.diag([1.0, 4.0])])
    >>> local_isotropy(J, (1.0, 1.0), (1.0, 1.0)).round(6).tolist()
    [1.0, 0.25]
    """
    sv = scaled_singular_values(jac, s_j, s_t, kind=kind)
    return _ratio(sv[..., -1], sv[..., 0])


@dataclass(frozen=True)
class GIIResult:
    """Eq. 11 over a workspace.

    ``sigma_min`` / ``sigma_max``: the smallest ``sigma_min`` and the largest ``sigma_max``
    of the scaled matrix over the feasible samples, attained at batch indices ``argmin`` /
    ``argmax`` (first in C order on ties; ``None`` with no feasible sample). ``count`` is
    the number of feasible samples. ``kind`` says which matrix was scaled.
    """

    value: float
    sigma_min: float
    sigma_max: float
    argmin: tuple[int, ...] | None
    argmax: tuple[int, ...] | None
    count: int
    kind: str = "jacobian"

    @property
    def weakest(self) -> tuple[int, ...] | None:
        """Where the normalised force ellipsoid's shortest semi-axis is shortest.

        ``argmin`` for a force map (its singular values are the semi-axes), ``argmax`` for
        our ``J`` (its singular values are their reciprocals).

        Returns
        -------
        tuple of int or None
            A batch index of the workspace.
        """
        return self.argmin if self.kind != "jacobian" else self.argmax

    @property
    def strongest(self) -> tuple[int, ...] | None:
        """Where the normalised force ellipsoid's longest semi-axis is longest.

        Returns
        -------
        tuple of int or None
            A batch index of the workspace.
        """
        return self.argmax if self.kind != "jacobian" else self.argmin


def feasible_mask(feasible: ArrayLike | None, batch: tuple[int, ...]) -> np.ndarray:
    if feasible is None:
        return np.ones(batch, dtype=bool)
    mask = np.asarray(feasible)
    if mask.dtype != np.bool_ or mask.shape != batch:
        raise ValueError(f"feasible must be a boolean array of the workspace shape {batch}, "
                         f"got {mask.dtype} {mask.shape}")
    return mask


def gii_from_extremes(sigma_min: ArrayLike, sigma_max: ArrayLike, feasible: ArrayLike | None = None, *,
                      kind: Kind = "jacobian") -> GIIResult:
    """Eq. 11 from each sample's smallest and largest scaled singular value, shape (...).

    For callers that compute the per-sample extremes themselves (a culling search keeps
    running extremes: ``min sigma_min / max sigma_max`` over the samples seen so far is an
    upper bound of the GII that only falls as samples are added).

    Parameters
    ----------
    sigma_min, sigma_max : array_like, shape (...)
        Each sample's smallest and largest scaled singular value (same shape).
    feasible : array_like of bool, shape (...), optional
        Samples to use; all when not given.
    kind : {"jacobian", "force_map", "velocity_map"}
        Which matrix the values came from (sets ``weakest`` / ``strongest``).

    Returns
    -------
    GIIResult

    Examples
    --------
    >>> r = gii_from_extremes([1.0, 2.0], [1.0, 4.0])
    >>> r.value, r.argmin, r.argmax, r.count
    (0.25, (0,), (1,), 2)
    """
    _check_kind(kind, RESULT_KINDS)
    lo = np.asarray(sigma_min, dtype=np.float64)
    hi = np.asarray(sigma_max, dtype=np.float64)
    if lo.shape != hi.shape:
        raise ValueError(f"sigma_min and sigma_max must have the same shape, got {lo.shape} and {hi.shape}")
    mask = feasible_mask(feasible, lo.shape)
    idx = np.flatnonzero(mask)
    return reduce_extremes(lo.reshape(-1)[idx], hi.reshape(-1)[idx], idx, lo.shape, kind)


def reduce_extremes(lo: FloatArray, hi: FloatArray, idx: np.ndarray, batch: tuple[int, ...], kind: str) -> GIIResult:
    """GII of feasible samples with flat indices ``idx`` into ``batch``."""
    if idx.size == 0:
        return GIIResult(float("nan"), float("nan"), float("nan"), None, None, 0, kind)
    i_lo = int(np.argmin(lo))           # first occurrence: ties go to the first sample
    i_hi = int(np.argmax(hi))
    smin, smax = float(lo[i_lo]), float(hi[i_hi])
    value = float(_ratio(np.float64(smin), np.float64(smax)))
    def where(k: int) -> tuple[int, ...]:
        return tuple(int(v) for v in np.unravel_index(idx[k], batch))

    return GIIResult(value, smin, smax, where(i_lo), where(i_hi), int(idx.size), kind)


def gii(jacobians: ArrayLike, s_j: ArrayLike, s_t: ArrayLike, feasible: ArrayLike | None = None, *,
        kind: Kind = "jacobian") -> GIIResult:
    """Global Isotropy Index (paper 001 eq. 11) over a workspace.

    Parameters
    ----------
    jacobians : array_like, shape (..., m, n)
        One matrix per workspace sample (every batch axis is the workspace); our ``J`` for
        ``kind="jacobian"``, the force map ``A`` (f = A tau) for ``kind="force_map"``.
    s_j : array_like, shape (n,)
        Actuator torque capabilities or ratios (eq. 12).
    s_t : array_like, shape (m,)
        Task requirements or ratios (eq. 13), SI (e.g. ``HUMAN_HAND_S_T``).
    feasible : array_like of bool, shape (...), optional
        Samples to use; the others are neither computed nor counted.

    Returns
    -------
    GIIResult
        ``value`` in [0, 1] (``nan`` with no feasible sample) and where the extremes are.

    Examples
    --------
    >>> J = np.stack([np.eye(2), np.diag([1.0, 4.0])])
    >>> r = gii(J, (1.0, 1.0), (1.0, 1.0))
    >>> round(r.value, 6), r.weakest, r.strongest
    (0.25, (1,), (0,))
    """
    mat = as_jacobian(jacobians, "jacobians")
    m, n = mat.shape[-2:]
    for name, vec, size in (("s_j", s_j, n), ("s_t", s_t, m)):
        if np.ndim(vec) != 1:
            raise ValueError(f"{name} must have shape ({size},) for a GII over one workspace, "
                             f"got {np.shape(vec)}")
    batch = mat.shape[:-2]
    mask = feasible_mask(feasible, batch)
    idx = np.flatnonzero(mask)
    flat = mat.reshape((-1, m, n))[idx]
    sv = scaled_singular_values(flat, s_j, s_t, kind=kind)
    return reduce_extremes(sv[:, -1], sv[:, 0], idx, batch, kind)


def rotate_task_rows(jac: ArrayLike, rotation: ArrayLike) -> FloatArray:
    """Express task rows in a rotated frame: ``blockdiag(R^T, R^T, ...) J``, shape (..., m, n).

    Moments keep their reference point; moving it is the mechanism's business.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        m a multiple of 3: rows ``(v, omega)`` (our ``J``) or ``(f, M)`` (a force map), in
        the base frame.
    rotation : array_like, shape (..., 3, 3)
        The end-effector frame's orientation in the base frame (columns are its axes).

    Returns
    -------
    ndarray, shape (..., m, n)
        The rows in the rotated frame.

    Examples
    --------
    >>> R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # 90 deg about z
    >>> rotate_task_rows(np.eye(3), R).tolist()
    [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    mat = as_jacobian(jac, "jac")
    rot = np.asarray(rotation, dtype=np.float64)
    m = mat.shape[-2]
    if m % 3:
        raise ValueError(f"jac must have a multiple of 3 task rows to rotate, got shape {mat.shape}")
    if rot.ndim < 2 or rot.shape[-2:] != (3, 3):
        raise ValueError(f"rotation must have shape (..., 3, 3), got {rot.shape}")
    rt = np.swapaxes(rot, -1, -2)
    blocks = [rt @ mat[..., 3 * b:3 * b + 3, :] for b in range(m // 3)]
    return np.concatenate(blocks, axis=-2)


