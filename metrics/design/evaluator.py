"""The base of every design evaluator: ``evaluate(design_ids, sample_ids)`` blocks for the searches.

In its own module so that evaluators defined elsewhere (``metrics.design.twin_batch``) and the
choice among them (``metrics.design.evaluators.make_evaluator``) import it without a cycle.
"""
from __future__ import annotations

import threading

import numpy as np

from kinematics.base import MechanismBase

from .study import Study


class Evaluator:
    """``evaluate(design_ids (k,), sample_ids (m,))`` for a study, plus what the searches need.

    ``samples`` are positions into ``study.workspace.points`` (an evaluator may drop samples
    no design can use, see ``TorqueOnly``); ``values(fields, sample_ids)`` evaluates designs
    given by their SI field values (``Study.field_values``), so designs off the grid (report
    checks) use the same code.
    """

    #: Cost of one (design, sample) pair relative to the vectorised evaluators' (1), for deciding
    #: whether a study is worth worker processes (``app.cli.optimize.auto_workers``).
    relative_cost = 1.0

    def __init__(self, study: Study) -> None:
        self.study = study
        self.form = study.objective.form
        self.samples = np.arange(study.n_samples)
        self.note = ""

    @property
    def n_samples(self) -> int:
        """Samples the searches see (``samples.size``; may be fewer than the workspace's).

        Returns
        -------
        int
        """
        return int(self.samples.size)

    def __call__(self, design_ids: np.ndarray, sample_ids: np.ndarray):
        return self.values(self.study.field_values(design_ids), self.samples[sample_ids])

    def values(self, fields: dict[str, np.ndarray], sample_pos: np.ndarray):   # pragma: no cover
        """Per-sample values of k designs given by their SI field values.

        Parameters
        ----------
        fields : dict of str to ndarray
            SI values of the varied fields, one row per design: shape (k,) for a scalar field,
            (k, n) for a per-actuator one (``Study.field_values``).
        sample_pos : ndarray of int, shape (m,)
            Positions into ``study.workspace.points``.

        Returns
        -------
        ndarray, shape (k, m), or a pair ``(a, b)`` of them for the GII
            The objective's per-sample values, ``nan`` where infeasible (0/1 for a count).
        """
        raise NotImplementedError

    def at(self, values: dict[str, float]):
        """Per-sample values of one design given by display values (on the grid or not).

        Parameters
        ----------
        values : dict of str to float
            Each grid parameter's value in its display unit.

        Returns
        -------
        ndarray, shape (1, n_samples)
            Over ``samples`` (a pair ``(a, b)`` of them for the GII).
        """
        mech = self.study.values_mechanism(values)
        fields = {}
        for p in self.study.parameters:
            for t in p.targets:
                v = getattr(mech.params, t.field)
                fields[t.field] = np.asarray(v, float)[None] if t.index is not None else np.array([float(v)])
        return self.values(fields, self.samples)

    def _finish(self, value: np.ndarray, feasible: np.ndarray) -> np.ndarray:
        """Objective values (k, m) from a quantity and the feasible mask."""
        obj = self.study.objective
        if obj.kind == "count_condition_above":
            with np.errstate(invalid="ignore"):
                return (feasible & (value > obj.threshold)).astype(np.float64)
        return np.where(feasible, value, np.nan)


class DesignModels:
    """One model per design, the last ``size`` kept: ``models(fields, i)`` is design ``i`` of a
    block (``fields`` as ``Evaluator.values`` takes them). Thread-safe (Dask runs threads)."""

    def __init__(self, base: MechanismBase, size: int = 64) -> None:
        self.base = base
        self.size = size
        self._mechs: dict[tuple, MechanismBase] = {}
        self._lock = threading.Lock()

    def __call__(self, fields: dict[str, np.ndarray], i: int) -> MechanismBase:
        changes = {}
        for name, v in fields.items():
            row = v[i]
            changes[name] = tuple(float(x) for x in row) if np.ndim(row) else float(row)
        key = tuple(sorted(changes.items()))
        with self._lock:
            mech = self._mechs.get(key)
        if mech is None:
            mech = self.base.replace(**changes)
            with self._lock:
                if len(self._mechs) >= self.size:
                    self._mechs.pop(next(iter(self._mechs)))
                self._mechs[key] = mech
        return mech
