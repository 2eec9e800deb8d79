"""The design-vectorised Twin-Pantograph (``metrics.design.twin_batch``, compiled) against the per-design
model evaluator (``Generic``: one ``TwinPantograph``, its ``force_map`` and a LAPACK SVD), the
culling search with it against brute force, and Table VII's study file against the paper's
tables. Headless, fixed seeds.
"""
from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest

from kinematics import TwinPantograph
from metrics.design import build_study, make_evaluator, run_study
from metrics.design.evaluators import Generic
from metrics.design.twin_batch import TwinBatch, force_gii_values, supports
from metrics.kernels.twin_batch import GAMMA, MAX_ROTATIONS
from metrics.orientations import rotation_count
from resources import load_study, study_schema

EPS = np.finfo(float).eps

#: A reduced Table VII: the paper's structure (l1, l2, l3, l6, tied waist torques Q1) on a
#: coarse grid and a coarse quarter workspace 25 cm away.
REDUCED = """
name = "reduced Table VII"
[mechanism]
kind = "twin_pantograph"
parameters = { unit_separation = 80.0, redundant_waist = "active", roll_actuator = "passive" }
[grid]
shoulder_separation = [24.0, 36.0]
upper_arm = { min = 125.0, max = 225.0, step = 25.0 }
forearm = { min = 175.0, max = 275.0, step = 25.0 }
pen_length = [70.0, 90.0]
Q1 = { targets = ["motor_torques.q1", "motor_torques.q4"], values = [0.12, 0.16, 0.20] }
[workspace]
kind = "grid"
axes = ["x", "y", "z"]
lower = [0.0, 0.0, -50.0]
upper = [80.0, 50.0, 50.0]
resolution = [3, 2, 3]
centre = { z = 250.0 }
[workspace.orientations]
tip_bound = 45.0
rings = 2
[objective]
kind = "gii"
S_T = "human_hand"
frame = "{frame}"
infeasible = "fail"
top_k = 3
"""


def reduced(frame: str = "end_effector", lever: float = 0.5):
    text = textwrap.dedent(REDUCED).replace("{frame}", frame)
    text = text.replace('roll_actuator = "passive" }', f'roll_actuator = "passive", ujoint_lever = {lever} }}')
    return build_study(study_schema.parse_study_text(text, "reduced_table7.toml", "reduced_table7"))


#: The eigenvalues' error in units of ``eps sigma_max^2``: forming ``G = M M^T`` (5 x 5 dot products of
#: 6 terms, ``|error| <= 6 eps |M| |M^T|``, Frobenius ``<= 6 eps |M|_F^2 <= 30 eps sigma_max^2``, M of
#: rank 5) and the kernel's Jacobi (``(GAMMA R + 1.5 D) eps tr G <= GAMMA MAX_ROTATIONS eps tr G``, the
#: R rotations and D drops being plane visits, ``tr G = |M|_F^2 <= 5 sigma_max^2``:
#: ``metrics.kernels.twin_batch``'s doc).
GRAM = 30 + 5 * GAMMA * MAX_ROTATIONS


def tolerance(a_ref: np.ndarray, b_ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Allowed |batch - reference| for sigma_min and sigma_max, per sample.

    The reference takes the SVD of M (error ~ eps sigma_max for every singular value); the
    batch the extreme eigenvalues of the Gram matrix M M^T, within ``GRAM eps sigma_max^2``, i.e.
    ``GRAM eps sigma_max^2 / (2 sigma)`` in sigma. The rows themselves (closed-form moments, R^T
    applied per row) differ by a few ulps of sigma_max: 64 eps sigma_max covers them and the SVD.
    The Jacobi term is a worst case (every rotation's rounding adding up); the errors measured
    are a few eps (``tests/metrics/test_twin_batch_kernel.py``).
    """
    return EPS * b_ref * (64 + 0.5 * GRAM * b_ref / a_ref), EPS * b_ref * (64 + 0.5 * GRAM)


@pytest.mark.parametrize("frame, lever", [("end_effector", 0.5), ("base", 0.5), ("end_effector", 1.0),
                                          ("base", 0.8)])
def test_batch_equals_the_model_on_random_designs(frame, lever):
    """Any U-joint lever (paper 001's adopted reading has 1.0): the batch's rows take ``h =
    ujoint_lever * l6``, the model places the U-joints there."""
    study = reduced(frame, lever)
    assert study.mechanism.params.ujoint_lever == lever
    rng = np.random.default_rng(7)
    k = 24
    # continuous designs in and beyond Table VII's box (many cannot reach every sample)
    fields = {"shoulder_separation": rng.uniform(0.024, 0.070, k), "upper_arm": rng.uniform(0.10, 0.30, k),
              "forearm": rng.uniform(0.15, 0.35, k), "pen_length": rng.uniform(0.07, 0.11, k)}
    motor = np.tile(np.asarray(study.mechanism.params.motor_torques), (k, 1))
    motor[:, [0, 3]] = rng.uniform(0.05, 0.30, k)[:, None]
    fields["motor_torques"] = motor
    pos = np.arange(study.n_samples)
    a_ref, b_ref = Generic(study).values(fields, pos)
    a, b = force_gii_values(study.mechanism, fields, study.workspace.points, s_t=study.objective.s_t, frame=frame)
    assert a.shape == b.shape == (k, study.n_samples)
    feas = ~np.isnan(a_ref)
    np.testing.assert_array_equal(~np.isnan(a), feas)          # the same feasibility, sample by sample
    assert feas.any() and (~feas).any()
    ta, tb = tolerance(a_ref[feas], b_ref[feas])
    assert np.all(np.abs(a[feas] - a_ref[feas]) <= ta)
    assert np.all(np.abs(b[feas] - b_ref[feas]) <= tb)


def test_a_pair_does_not_depend_on_the_call():
    """The culling search's requirement: the same bits whatever other pairs share the call."""
    study = reduced()
    ev = make_evaluator(study)
    assert isinstance(ev, TwinBatch)
    ids = np.array([3, 40, 41, 42, 150, 299], np.int64)       # 40..42: one geometry, three Q1
    samples = np.arange(study.n_samples, dtype=np.int64)
    a, b = ev(ids, samples)
    for i, d in enumerate(ids):
        sub = samples[::7]
        a1, b1 = ev(np.array([d]), sub)
        np.testing.assert_array_equal(a1[0], a[i, sub])
        np.testing.assert_array_equal(b1[0], b[i, sub])


def test_culling_with_the_batch_equals_brute_force():
    study = reduced()
    brute = run_study(study, method="brute_force", with_report=False)
    for chunks in (None, 5):                 # one search, and chunks with floors and handed-on probes
        cull = run_study(study, method="culling", chunks=chunks, with_report=False)
        np.testing.assert_array_equal(cull.top_designs, brute.top_designs)
        np.testing.assert_array_equal(cull.top_values, brute.top_values)
        assert cull.evaluations < brute.evaluations
    assert np.all(np.isfinite(brute.top_values)) and brute.top_values[0] > 0


def test_the_batch_ranks_like_the_model():
    """Brute force with the model's evaluator finds the same top designs (values within tolerance)."""
    study = reduced()
    ids = np.arange(study.n_designs)
    samples = np.arange(study.n_samples)
    model = Generic(study)
    a_ref, b_ref = model(ids, samples)
    with np.errstate(invalid="ignore"):
        gii_ref = np.where(np.isnan(a_ref).any(1), -np.inf, np.nanmin(a_ref, 1) / np.nanmax(b_ref, 1))
    best = run_study(study, method="brute_force", with_report=False)
    ref_order = np.lexsort((ids, -gii_ref))[:3]
    np.testing.assert_array_equal(best.top_designs, ref_order)
    # GII = min a / max b: at the sample attaining min a, kappa <= max b / min a = 1 / GII, so
    # tolerance() gives a relative error of eps (64 kappa + GRAM kappa^2 / 2) in min a and
    # eps (64 + GRAM / 2) in max b.
    kappa = 1.0 / gii_ref[ref_order]
    rel = EPS * (64 * kappa + 0.5 * GRAM * kappa ** 2 + 64 + 0.5 * GRAM)
    np.testing.assert_allclose(best.top_values, gii_ref[ref_order], rtol=0,
                               atol=float(np.max(rel * gii_ref[ref_order])))


def test_supports_only_the_five_dof_force_gii():
    study = reduced()
    assert supports(study)
    six = TwinPantograph(roll_actuator="active", redundant_waist="passive")
    from dataclasses import replace
    assert not supports(replace(study, mechanism=six))
    with pytest.raises(ValueError, match="5-DOF"):
        force_gii_values(six, {}, np.zeros((1, 6)), s_t=(1.0,) * 5)
    # A task point off the U-joints' midpoint is the model's alone (Generic).
    for off in ({"reference_along": -1.0}, {"reference_offset": 0.01}):
        moved = study.mechanism.replace(**off)
        assert not supports(replace(study, mechanism=moved))
        with pytest.raises(ValueError, match="midpoint"):
            force_gii_values(moved, {}, study.workspace.points, s_t=(1.0,) * 5)
    assert supports(reduced(lever=1.0))
    with pytest.raises(ValueError, match="fields must be among"):
        force_gii_values(study.mechanism, {"ujoint_limit": np.array([1.0])}, study.workspace.points, s_t=(1.0,) * 5)


# Paper 001, Table VII (cm; Q1 dimensionless): min, max, step, the printed total per row.
TABLE_VII = {"shoulder_separation": (2.4, 7.0, 0.2, 24), "upper_arm": (10.0, 30.0, 0.5, 41),
             "forearm": (15.0, 35.0, 0.5, 41), "pen_length": (7.0, 11.0, 0.2, 21), "Q1": (0.5, 3.0, 0.1, 26)}
TABLE_VII_TOTAL = 22_027_824
# Table VI: position axes (cm) min, max, step, total; 617 orientations within 45 deg; total.
TABLE_VI = {"x": (0.0, 8.0, 0.5, 17), "y": (0.0, 5.0, 0.5, 11), "z": (-5.0, 5.0, 0.5, 21)}
TABLE_VI_ORIENTATIONS = 617
TABLE_VI_TOTAL = 2_422_959


def test_table7_counts_follow_from_the_tables():
    for lo, hi, step, total in list(TABLE_VII.values()) + list(TABLE_VI.values()):
        assert round((hi - lo) / step) + 1 == total
    assert math.prod(t[3] for t in TABLE_VII.values()) == TABLE_VII_TOTAL
    # eq. 16 with N = 14 rings is the only ring count giving Table VI's 617 directions
    counts = [rotation_count(math.radians(45.0), n) for n in range(1, 30)]
    assert counts.count(TABLE_VI_ORIENTATIONS) == 1 and counts.index(TABLE_VI_ORIENTATIONS) + 1 == 14
    assert math.prod(t[3] for t in TABLE_VI.values()) * TABLE_VI_ORIENTATIONS == TABLE_VI_TOTAL

    study = build_study(load_study("twin_pantograph_table7"))
    assert (study.n_designs, study.n_samples) == (TABLE_VII_TOTAL, TABLE_VI_TOTAL)
    shoulder = study.mechanism.params.motor_torques[1]
    for p in study.parameters:
        lo, hi, step, total = TABLE_VII[p.name]
        want = np.linspace(lo, hi, total) * (10.0 if p.name != "Q1" else shoulder)   # cm -> mm; Q1 -> N m
        np.testing.assert_allclose(p.display, want, rtol=1e-12)
    pts = study.workspace.points
    for j, (lo, hi, step, total) in enumerate(TABLE_VI.values()):
        centre = 0.25 if j == 2 else 0.0
        np.testing.assert_allclose(np.unique(pts[:, j].round(9)), np.linspace(lo, hi, total) / 100 + centre,
                                   atol=1e-12)
    assert study.workspace.orientations == TABLE_VI_ORIENTATIONS
    assert isinstance(make_evaluator(study), TwinBatch)


def test_local_processes_read_the_shared_study_and_agree(tmp_path, monkeypatch):
    """``LocalPool.share``: the study goes to the workers as a file read once per process."""
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))     # where SharedFile writes (mkstemp's default)
    study = reduced()
    brute = run_study(study, method="brute_force", with_report=False)
    par = run_study(study, workers=2, chunks=4, with_report=False)
    assert par.engine == "processes"
    np.testing.assert_array_equal(par.top_designs, brute.top_designs)
    np.testing.assert_array_equal(par.top_values, brute.top_values)
    assert not list(tmp_path.glob("isoforce-study-*.pickle"))     # removed when the pool closed
