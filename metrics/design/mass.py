"""The apparent mass in design studies: the ``max_apparent_mass`` bound and the
``min_force_per_apparent_mass`` objective (table in ``metrics.design.study``).

``ApparentMass`` wraps the evaluator of the study's objective without the mass (``without_mass``)
and takes, per (design, sample), the largest apparent mass ``m(p, x)``: ``metrics.quantities``
``apparent_mass_max``, the reciprocal of the smallest eigenvalue of the force block of
``Lambda^-1 = J M^-1 J^T`` (links and reflected rotors ``J_u N_u^2``; ``inf`` where the handle
cannot move along some direction).

- ``min_force_per_apparent_mass``: ``f(p, x) = F_iso(p, x) / m(p, x)`` in N/kg (= m/s^2).
- ``max_apparent_mass = m_max``: where ``m(p, x) > m_max`` at a sample the objective counts as
  feasible, the value becomes ``ranking.VETO`` (a count: ``inf``), so the design ranks after
  every feasible one whatever ``infeasible`` says, and the culling search drops it on the
  first such sample it meets (its bound cannot rise again).

Both depend on the (design, sample) pair alone, as the searches' exactness needs.

Cost. The mass is computed only for the pairs the search evaluates, and only for studies
that ask. Two ways, both exact up to rounding (tested against ``metrics.quantities.evaluate``):

==================  ============================================================================
``rotor-split``     grids of ``gear_ratios`` / ``motor_torques`` only: the geometry is shared, and
                    the kinetic form is linear in the reflected rotor inertias, ``K_d = K_fixed +
                    sum_i (N_i,d / N_i,0)^2 P_i`` over the varied ratios ``i``; ``K_fixed`` and
                    ``P_i`` (rotor ``i`` alone) come from ``2 + v`` kinetic forms of the base model,
                    each design then costs an ``m x m`` inverse and eigenvalues per sample
``per design``      otherwise: one model per design, ``metrics.quantities.evaluate`` of
                    ``apparent_mass_max`` on the samples asked (finite differences of the body
                    poses, about ten static quantities per sample)
==================  ============================================================================
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from kinematics.base import MechanismBase

from .. import dynamics, wrenches
from ..quantities import evaluate
from .evaluator import DesignModels, Evaluator
from .ranking import VETO
from .study import DIRECTIONS, Study

#: The mass-free objective each kind is evaluated with before ``ApparentMass`` adds the mass.
BASE_KIND = {"min_force_per_apparent_mass": "min_isotropic_force"}


def without_mass(study: Study) -> Study:
    """The study without the mass: no bound, and ``min_isotropic_force`` for the force-per-mass kind.

    Parameters
    ----------
    study : Study

    Returns
    -------
    Study
        Same grid, workspace and fingerprint.
    """
    kind = BASE_KIND.get(study.objective.kind, study.objective.kind)
    return replace(study, objective=replace(study.objective, kind=kind, direction=DIRECTIONS[kind],
                                            max_apparent_mass=None))


def veto(out, over: np.ndarray, form: str):
    """Objective values with the over-bound pairs vetoed (``VETO``; a count: ``inf``).

    Parameters
    ----------
    out : ndarray (k, m), or a pair of them in the ratio form
        The evaluator's values.
    over : ndarray of bool, shape (k, m)
        Pairs whose largest apparent mass exceeds the bound.
    form : {"min", "ratio", "sum"}

    Returns
    -------
    Same structure as ``out``; a pair the objective already calls infeasible is left alone.

    Examples
    --------
    >>> veto(np.array([[1.0, np.nan, 2.0]]), np.array([[True, True, False]]), "min").tolist()
    [[-1.7976931348623157e+308, nan, 2.0]]
    """
    if form == "sum":
        return np.where(over, np.inf, out)
    if form == "ratio":
        a, b = (np.asarray(v, float) for v in out)
        ok = ~(np.isnan(a) | (a == -np.inf) | np.isnan(b) | (b == -np.inf))
        return np.where(over & ok, VETO, a), b
    f = np.asarray(out, float)
    ok = ~(np.isnan(f) | (f == -np.inf))
    return np.where(over & ok, VETO, f)


class _RotorSplit:
    """``K_fixed`` and the pieces ``P_i`` of the kinetic form over the samples (see the module doc)."""

    def __init__(self, mech: MechanismBase, points: np.ndarray, varied: list[int]) -> None:
        q, ok = mech.inverse(points)
        feas = ok.copy()
        if ok.any():
            feas[ok] = mech.feasible(q[ok], points[ok])
        self.feasible = feas
        self.joint = mech.mass_coordinates == "joint"
        self.varied = varied
        self.gear0 = np.asarray(mech.params.gear_ratios, float)[varied]
        rotors = np.asarray(mech.params.rotor_inertias, float)
        qf, xf = q[feas], points[feas]

        def form(r, with_rotors=True):
            m = mech.replace(rotor_inertias=tuple(float(v) for v in r))
            if self.joint:
                return m.mass_matrix(qf, xf, rotors=with_rotors)
            return m.task_inertia(qf, xf, rotors=with_rotors)

        fixed = rotors.copy()
        fixed[varied] = 0.0
        self.fixed = form(fixed)
        links = form(rotors, with_rotors=False)
        self.pieces = []
        for i in varied:
            only = np.zeros_like(rotors)
            only[i] = rotors[i]
            self.pieces.append(form(only) - links)
        self.jac = mech.jacobian(qf, xf) if self.joint else None
        self.rows = wrenches.force_rows(mech)
        self.index = np.full(points.shape[0], -1)
        self.index[feas] = np.arange(int(feas.sum()))

    def masses(self, gear: np.ndarray, sample_pos: np.ndarray) -> np.ndarray:
        """Largest apparent mass (k, m) of designs with ``gear`` (k, n) ratios; ``nan`` where infeasible."""
        k = gear.shape[0]
        out = np.full((k, sample_pos.size), np.nan)
        at = self.index[sample_pos]
        live = at >= 0
        if not live.any():
            return out
        rows = at[live]
        scale = (gear[:, self.varied] / self.gear0) ** 2                      # (k, v)
        form = self.fixed[rows][None] + np.einsum("kv,vsab->ksab", scale, np.stack([p[rows] for p in self.pieces]))
        if self.joint:
            mob = dynamics.mobility(np.broadcast_to(self.jac[rows], form.shape[:2] + self.jac.shape[1:]), form)
        else:
            mob = dynamics.inverse_spd(form)
        out[:, live] = dynamics.apparent_mass_range(mob, self.rows)[..., 1]
        return out


class ApparentMass(Evaluator):
    """The study's objective with the apparent mass: force per mass, or the mass bound, or both
    (see the module docstring). ``inner`` evaluates ``without_mass(study)``; its samples are kept."""

    def __init__(self, study: Study, inner: Evaluator) -> None:
        super().__init__(study)
        self.inner = inner
        self.relative_cost = inner.relative_cost
        self.samples = inner.samples
        self.points = study.workspace.points
        mech = study.mechanism
        fields = {t.field for p in study.parameters for t in p.targets}
        params = mech.params
        self.split = None
        if (fields <= {"gear_ratios", "motor_torques"} and not mech.is_redundant
                and len(getattr(params, "rotor_inertias", ())) == len(params.gear_ratios)):
            varied = sorted({t.index for p in study.parameters for t in p.targets if t.field == "gear_ratios"})
            self.split = _RotorSplit(mech, self.points, varied)
        self._mech = DesignModels(mech)
        obj = study.objective
        what = []
        if obj.kind == "min_force_per_apparent_mass":
            what.append("force / largest apparent mass")
        if obj.max_apparent_mass is not None:
            what.append(f"largest apparent mass <= {obj.max_apparent_mass:g} kg")
        how = "rotor inertias split once" if self.split is not None else "one model per design"
        self.note = f"{inner.note}; {' and '.join(what)} ({how})"

    def masses(self, fields: dict[str, np.ndarray], sample_pos: np.ndarray) -> np.ndarray:
        """Largest apparent mass of each design at each sample, kg.

        Parameters
        ----------
        fields : dict of str to ndarray
            SI values of the varied fields, one row per design (``Study.field_values``).
        sample_pos : ndarray of int, shape (m,)
            Positions into ``study.workspace.points``.

        Returns
        -------
        ndarray, shape (k, m)
            ``nan`` where the pose is infeasible, ``inf`` where the handle cannot move.
        """
        k = next(iter(fields.values())).shape[0]
        if self.split is not None:
            base = np.asarray(self.study.mechanism.params.gear_ratios, float)
            gear = np.asarray(fields.get("gear_ratios", np.broadcast_to(base, (k, base.size))), float)
            return self.split.masses(gear, sample_pos)
        x = self.points[sample_pos]
        out = np.empty((k, sample_pos.size))
        for i in range(k):
            ev = evaluate(self._mech(fields, i), x, ("apparent_mass_max",))
            out[i] = np.where(ev.feasible, ev.values["apparent_mass_max"], np.nan)
        return out

    def values(self, fields, sample_pos):
        """The objective's values with the apparent mass; as ``Evaluator.values``."""
        out = self.inner.values(fields, sample_pos)
        mass = self.masses(fields, sample_pos)
        obj = self.study.objective
        if obj.kind == "min_force_per_apparent_mass":
            with np.errstate(invalid="ignore", divide="ignore"):
                out = np.asarray(out, float) / mass          # inf mass: 0 N/kg (cannot accelerate)
        if obj.max_apparent_mass is not None:
            with np.errstate(invalid="ignore"):
                out = veto(out, mass > obj.max_apparent_mass, self.form)
        return out
