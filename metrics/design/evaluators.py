"""How designs are evaluated: ``f(design, sample)`` blocks for the searches.

``make_evaluator`` picks the fastest exact one: ``TorqueOnly`` when the grid varies torques or
gear ratios only (J's column norms are computed once), ``SensorOnly`` likewise for the sensor
GII (the velocity map ``K`` computed once), ``FiveBarBatch`` for five-bar link
lengths (``metrics.design.batch``: designs broadcast against points, no model per design),
else ``Generic`` (one model per design, ``metrics.quantities.evaluate`` or the scaled
singular values of ``metrics.gii``). Each gives a (design, sample) value that does not depend
on which other pairs share the call, which the searches' exactness needs.
"""
from __future__ import annotations

import threading

import numpy as np

from kinematics import kind_of

from .. import gii as gii_mod
from .. import sensor_gii
from ..quantities import evaluate
from .batch import fivebar_batch, isotropic_force_fast
from .evaluator import DesignModels, Evaluator
from .mass import ApparentMass, without_mass
from .objective_rules import HUMAN_HAND_TASK
from .study import Study
from .twin_batch import TwinBatch
from .twin_batch import supports as twin_batch_supports


class FiveBarBatch(Evaluator):
    """Five-bar designs vectorised with ``metrics.design.batch.fivebar_batch``."""

    FIELDS = {"proximal", "distal", "half_base", "motor_torques", "gear_ratios"}

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        self.points = study.workspace.points
        self.sampling = study.workspace.sampling
        self.note = "design-vectorised five-bar (metrics.design.batch)"

    def values(self, fields, sample_pos):
        """Per-sample values, all designs in one broadcast pass (arguments and shapes: ``Evaluator.values``)."""
        p = self.study.mechanism.params
        k = next(iter(fields.values())).shape[0]

        def col(name):
            v = fields.get(name)
            return getattr(p, name) if v is None else v.reshape(k, 1)

        a1, a2, a3 = col("proximal"), col("distal"), col("half_base")
        if "motor_torques" in fields or "gear_ratios" in fields:
            motor = fields.get("motor_torques", np.asarray(p.motor_torques, float)[None])
            gear = fields.get("gear_ratios", np.asarray(p.gear_ratios, float)[None])
            t = motor * gear
            t0, t1 = t[:, 0:1], t[:, 1:2]
        else:
            t0, t1 = (m * g for m, g in zip(p.motor_torques, p.gear_ratios))
        pts = self.points[sample_pos]
        px, py = pts[None, :, 0], pts[None, :, 1]
        obj = self.study.objective
        normalised = self.sampling is not None and self.sampling.frame == "normalised"
        if obj.kind == "count_condition_above":
            a1, a2, a3 = (np.broadcast_to(np.asarray(v, float), (k, 1)) for v in (a1, a2, a3))
            if normalised:
                s = (a1 + a2 + a3) / 3.0
                a1, a2, a3 = a1 / s, a2 / s, a3 / s       # metrics.sweeps.Sampling.mechanism
            out = fivebar_batch(a1, a2, a3, pts[None], quantities=("condition_number",),
                                working_mode=p.working_mode)
            return self._finish(out.values["condition_number"], out.feasible)
        if normalised:                                    # physical frame for forces
            s = (np.asarray(a1) + a2 + a3) / 3.0
            px, py = px * s, py * s
        f = isotropic_force_fast(a1, a2, a3, px, py, t0, t1, p.working_mode)
        return np.broadcast_to(f, (k, pts.shape[0]))


class TorqueOnly(Evaluator):
    """Grids that vary torques or gear ratios only, objective ``min_isotropic_force``: the
    geometry, hence J's column norms and the feasible set, is the same for every design, so
    they are computed once; ``F = min_x min_u t_u / |J[:, u]|`` per design is then a few
    array operations. With ``infeasible = "skip"`` the samples outside the feasible set are
    dropped up front (they would be skipped for every design)."""

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        ev = evaluate(study.mechanism, study.workspace.points, ("column_norms",))
        self.norms = ev.values["column_norms"]
        self.feasible = ev.feasible
        if study.objective.infeasible == "skip":
            self.samples = np.flatnonzero(ev.feasible)
        self.note = (f"column norms cached once ({int(ev.feasible.sum())} of {ev.feasible.size} samples feasible"
                     + ("; the others dropped" if study.objective.infeasible == "skip" else "") + ")")

    def values(self, fields, sample_pos):
        """Per-sample values from the cached column norms (arguments and shapes: ``Evaluator.values``)."""
        p = self.study.mechanism.params
        k = next(iter(fields.values())).shape[0]
        n = len(p.motor_torques)
        motor = fields.get("motor_torques", np.broadcast_to(np.asarray(p.motor_torques, float), (k, n)))
        gear = fields.get("gear_ratios", np.broadcast_to(np.asarray(p.gear_ratios, float), (k, n)))
        t = np.asarray(motor, float) * np.asarray(gear, float)
        if t.shape[1] != self.norms.shape[1]:                # pragma: no cover - model mismatch
            raise ValueError(f"{t.shape[1]} torque limits for {self.norms.shape[1]} Jacobian columns")
        norms = self.norms[sample_pos]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.min(t[:, None, :] / norms[None, :, :], axis=-1)
        return np.where(self.feasible[sample_pos][None, :], f, np.nan)


class Generic(Evaluator):
    """Any mechanism and parameter: one model per design, ``metrics.quantities.evaluate`` (or
    the GII's scaled singular values) on the requested samples."""

    CACHE = 64
    #: One model and one LAPACK call per design: ~100x a vectorised evaluator's pair.
    relative_cost = 100.0

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        self.points = study.workspace.points
        self._mech = DesignModels(study.mechanism, self.CACHE)
        self.note = "one model per design (metrics.quantities.evaluate)"
        if study.objective.kind in ("gii", "sensor_gii"):
            self.note = "one model per design, scaled singular values (metrics.gii)"

    def values(self, fields, sample_pos):
        """Per-sample values, one model per design (arguments and shapes: ``Evaluator.values``)."""
        k = next(iter(fields.values())).shape[0]
        x = self.points[sample_pos]
        obj = self.study.objective
        if obj.kind in ("gii", "sensor_gii"):
            a = np.empty((k, x.shape[0]))
            b = np.empty((k, x.shape[0]))
            for i in range(k):
                a[i], b[i] = self._gii_rows(self._mech(fields, i), x)
            return a, b
        q = "condition_number" if obj.kind == "count_condition_above" else "isotropic_force"
        out = np.empty((k, x.shape[0]))
        for i in range(k):
            ev = evaluate(self._mech(fields, i), x, (q,))
            out[i] = self._finish(ev.values[q][None], ev.feasible[None])[0]
        return out

    def _gii_rows(self, mech, x):
        obj = self.study.objective
        qj, ok = mech.inverse(x)
        feas = ok.copy()
        if ok.any():
            feas[ok] = mech.feasible(qj[ok], x[ok])
        a = np.full(x.shape[0], np.nan)
        b = np.full(x.shape[0], np.nan)
        if not feas.any():
            return a, b
        xf, qf = x[feas], qj[feas]
        if obj.kind == "sensor_gii":
            sv = _sensor_singular_values(self.study, mech, qf, xf)
            a[feas], b[feas] = sv[:, -1], sv[:, 0]
            return a, b
        if mech.is_redundant or mech.has_orientation:           # wrench devices: the paper's force map
            mat, kind = mech.force_map(qf, xf), "force_map"
        else:
            mat, kind = mech.jacobian(qf, xf), "jacobian"
        if obj.frame == "end_effector":
            mat = _rows_in_tool_frame(mech, mat, xf)
        sv = gii_mod.scaled_singular_values(mat, mech.torque_limits(), obj.s_t, kind=kind)
        a[feas], b[feas] = sv[:, -1], sv[:, 0]
        return a, b


def _rows_in_tool_frame(mech, mat: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Task rows in the pen frame (paper 001: "the Jacobian is expressed in the end-effector
    coordinate frame prior to scaling", because Table I is relative to the hand).

    6-DOF rows ``(f, m)`` (or ``(v, omega)``) in the base frame: ``blockdiag(R^T, R^T)``. 5-DOF
    pen rows ``(f, m . a, m . b)`` (``kinematics.twin_pantograph``): the moment rows already are
    pen-frame components, so only the force rows turn, ``R^T f``.
    """
    from kinematics.rotations import rotation_matrix, tilt_matrix

    names = mech.task_names
    if names == ("x", "y", "z", "rx", "ry", "rz"):
        return gii_mod.rotate_task_rows(mat, rotation_matrix(x[..., 3:6]))
    if names == ("x", "y", "z", "rx", "rz"):
        rt = np.swapaxes(tilt_matrix(x[..., 3:5]), -1, -2)
        out = mat.copy()
        out[..., :3, :] = rt @ mat[..., :3, :]
        return out
    raise ValueError(f"frame 'end_effector' needs pen task coordinates, got {names}")


def sensor_resolutions(mech) -> np.ndarray:
    """Joint-side sensor resolutions of the actuated joints, up to a common factor, shape (n,).

    Identical encoders on every motor (``metrics.design.study``): counts per joint radian are
    proportional to the transmission ratio, so the actuated joints' ``gear_ratios``.

    Parameters
    ----------
    mech : MechanismBase

    Returns
    -------
    ndarray, shape (n,)
    """
    g = np.asarray(mech.params.gear_ratios, dtype=np.float64)
    return g if g.shape[-1] == mech.n_joints else g[list(mech.actuated)]     # Twin-Pantograph: 7 entries


def hand_velocities(study: Study) -> tuple[float, ...]:
    """The sensor GII's ``S_T`` (SI): the study's numbers, else paper 001 eq. 27 for its task rows.

    Parameters
    ----------
    study : Study

    Returns
    -------
    tuple of float, length m
    """
    if study.objective.s_t is not None:
        return study.objective.s_t
    return tuple(gii_mod.HUMAN_HAND_VELOCITIES[HUMAN_HAND_TASK.index(n)] for n in study.mechanism.task_names)


def _velocity_maps(study: Study, mech, q: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``K = A^T`` (k, n, m) at reachable samples, task columns in the objective's frame."""
    mat = mech.force_map(q, x)
    if study.objective.frame == "end_effector":
        mat = _rows_in_tool_frame(mech, mat, x)
    return np.swapaxes(mat, -1, -2)


def _sensor_singular_values(study: Study, mech, q: np.ndarray, x: np.ndarray) -> np.ndarray:
    return sensor_gii.velocity_singular_values(_velocity_maps(study, mech, q, x), sensor_resolutions(mech),
                                            hand_velocities(study))


class SensorOnly(Evaluator):
    """Sensor GII over grids that vary gear ratios or torques only: the geometry, hence the
    velocity map ``K`` and the feasible set, is the same for every design, so they are computed
    once; each design is then a batched SVD of ``S_J K S_T`` (``metrics.gii``). With
    ``infeasible = "skip"`` the samples no design reaches are dropped up front."""

    def __init__(self, study: Study) -> None:
        super().__init__(study)
        mech = study.mechanism
        x = study.workspace.points
        q, ok = mech.inverse(x)
        feas = ok.copy()
        if ok.any():
            feas[ok] = mech.feasible(q[ok], x[ok])
        self.feasible = feas
        self.maps = np.full((x.shape[0], mech.n_joints, mech.task_dim), np.nan)
        if feas.any():
            self.maps[feas] = _velocity_maps(study, mech, q[feas], x[feas])
        self.velocities = hand_velocities(study)
        if study.objective.infeasible == "skip":
            self.samples = np.flatnonzero(feas)
        self.note = (f"velocity map cached once ({int(feas.sum())} of {feas.size} samples feasible"
                     + ("; the others dropped" if study.objective.infeasible == "skip" else "") + ")")

    def values(self, fields, sample_pos):
        """Per-sample ``(sigma_min, sigma_max)`` of the scaled velocity map, ``nan`` where infeasible.

        Arguments as ``Evaluator.values``; returns the pair ``(a, b)``, each of shape (k, m).
        """
        base = self.study.mechanism
        k = next(iter(fields.values())).shape[0]
        gear = fields.get("gear_ratios", np.broadcast_to(np.asarray(base.params.gear_ratios, float),
                                                         (k, len(base.params.gear_ratios))))
        gear = np.asarray(gear, dtype=np.float64)
        res = gear if gear.shape[1] == base.n_joints else gear[:, list(base.actuated)]   # as sensor_resolutions
        feas = self.feasible[sample_pos]
        a = np.full((k, sample_pos.size), np.nan)
        b = np.full((k, sample_pos.size), np.nan)
        maps = self.maps[sample_pos][feas]
        for i, r in enumerate(res):
            sv = sensor_gii.velocity_singular_values(maps, r, self.velocities)
            a[i, feas], b[i, feas] = sv[:, -1], sv[:, 0]
        return a, b


def make_evaluator(study: Study) -> Evaluator:
    """The fastest exact evaluator for the study (see the classes above).

    A study that bounds the apparent mass, or optimizes force per apparent mass, gets
    ``metrics.design.mass.ApparentMass`` around the evaluator of its objective without the mass
    (``min_isotropic_force`` for the force-per-mass kind).

    Parameters
    ----------
    study : Study
        A built study (``build_study``).

    Returns
    -------
    Evaluator
        ``TorqueOnly``, ``SensorOnly``, ``FiveBarBatch``, ``TwinBatch``, ``Generic``, or
        ``ApparentMass`` around one of them.
    """
    if study.objective.uses_mass:
        return ApparentMass(study, make_evaluator(without_mass(study)))
    fields = {t.field for p in study.parameters for t in p.targets}
    kind = study.objective.kind
    if kind == "sensor_gii" and fields <= {"motor_torques", "gear_ratios"} and study.workspace.sampling is None:
        return SensorOnly(study)        # (torques do not enter the sensor GII; ratios only scale K's rows)
    if kind == "min_isotropic_force" and fields <= {"motor_torques", "gear_ratios"} \
            and study.workspace.sampling is None and not study.mechanism.is_redundant:
        return TorqueOnly(study)        # (redundant actuation: a zonotope, not J's column norms)
    if kind_of(study.mechanism) == "fivebar" and kind not in ("gii", "sensor_gii") and fields <= FiveBarBatch.FIELDS \
            and study.mechanism.params.joint_limits is None:
        return FiveBarBatch(study)
    if twin_batch_supports(study):
        return TwinBatch(study)
    if study.workspace.sampling is not None:
        raise ValueError("a 'sampling' workspace needs the design-vectorised five-bar evaluator")
    return Generic(study)


_EVALUATORS: dict[str, Evaluator] = {}
_EVALUATORS_LOCK = threading.Lock()


def evaluator_for(study: Study) -> Evaluator:
    """``make_evaluator``, built once per process (workers reuse it across chunks).

    Parameters
    ----------
    study : Study
        A built study; keyed by its ``fingerprint``.

    Returns
    -------
    Evaluator
    """
    key = study.fingerprint or str(id(study))
    with _EVALUATORS_LOCK:
        ev = _EVALUATORS.get(key)
    if ev is None:
        ev = make_evaluator(study)
        with _EVALUATORS_LOCK:
            if len(_EVALUATORS) > 16:
                _EVALUATORS.clear()
            _EVALUATORS[key] = ev
    return ev


def largest_apparent_mass(study: Study, design_ids) -> np.ndarray:
    """Each design's largest apparent mass over the samples the search uses (feasible ones), kg.

    Parameters
    ----------
    study : Study
        A study whose objective uses the mass (``Objective.uses_mass``).
    design_ids : array_like of int, shape (k,)

    Returns
    -------
    ndarray, shape (k,)
        ``nan`` for a design with no feasible sample.
    """
    ev = evaluator_for(study)
    ids = np.asarray(design_ids, np.int64)
    out = np.full(ids.size, np.nan)
    for j, d in enumerate(ids):
        m = ev.masses(study.field_values([d]), ev.samples)[0]
        m = m[~np.isnan(m)]
        if m.size:
            out[j] = m.max()
    return out
