"""The shipped sensor-resolution study (paper 001 Table IX) and the ``sensor_gii`` objective.

The study file loads with its per-distance designs; a reduced run finds an interior optimum
that brute force and an independent evaluation (model -> ``metrics.sensor_gii.velocity_gii``) agree
on; the fast evaluator equals the one-model-per-design one; bad keys name the file and key.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from metrics import sensor_gii as SG
from metrics.design import build_study, run_study
from metrics.design.evaluators import make_evaluator
from resources import StudyError, load_study
from resources.study_schema import parse_study_text, study_from_data

KEY = "twin_pantograph_sensor"


@pytest.fixture(scope="module")
def spec():
    return load_study(KEY)


def test_study_file_loads_with_a_design_per_distance(spec):
    assert spec.objective.kind == "sensor_gii" and spec.objective.s_t_name == "hand_velocity"
    assert spec.series.values == (100.0, 150.0, 200.0, 250.0, 300.0, 350.0, 400.0)
    runs = spec.runs
    assert [r.series_value for r in runs] == list(spec.series.values)
    per_value = dict(spec.series.parameters)
    for i, r in enumerate(runs):                     # [series] parameters reach each run's model (mm -> m)
        p = r.mechanism.params
        assert p.upper_arm == pytest.approx(per_value["upper_arm"][i] / 1e3, rel=1e-15)
        assert p.pen_length == pytest.approx(per_value["pen_length"][i] / 1e3, rel=1e-15)
    (q1,) = spec.grid
    assert [t.label for t in q1.targets] == ["gear_ratios.q1", "gear_ratios.q4"]   # Q1 on the waists


def _reduced(spec, distance_mm: float, values: list[float]):
    """One run of the shipped study at one distance with a shorter list of ratios."""
    data = copy.deepcopy(spec.raw)
    i = data["series"]["values"].index(distance_mm)
    data.pop("series")
    data["workspace"]["centre"] = {"z": distance_mm}
    for name, vals in spec.raw["series"]["parameters"].items():
        data["mechanism"]["parameters"][name] = vals[i]
    data["grid"]["Q1"] = {"targets": ["gear_ratios.q1", "gear_ratios.q4"], "values": values}
    return build_study(study_from_data(data, f"{KEY}.toml", KEY))


def test_reduced_run_finds_an_interior_optimum_that_brute_force_and_the_model_confirm(spec):
    values = [round(0.6 + 0.2 * i, 10) for i in range(10)]          # 0.6 .. 2.4
    study = _reduced(spec, 250.0, values)
    assert type(make_evaluator(study)).__name__ == "SensorOnly"
    cull = run_study(study, top_k=2)
    brute = run_study(study, method="brute_force", top_k=2)
    assert np.array_equal(cull.top_designs, brute.top_designs)
    assert np.allclose(cull.top_values, brute.top_values, rtol=1e-12)
    best = int(cull.top_designs[0])
    assert 0 < best < len(values) - 1                                # a maximum inside the range, not at an end
    # independently: the model's IK and force map, K = A^T, metrics.sensor_gii.velocity_gii
    mech = study.mechanism
    x = study.workspace.points
    q, ok = mech.inverse(x)
    assert ok.all() and mech.feasible(q, x).all()
    k = np.swapaxes(mech.force_map(q, x), -1, -2)
    ratio = values[best]
    direct = SG.velocity_gii(k, [ratio, 1, 1, ratio, 1, 1], [5.0, 5.0, 5.0, 30.0, 30.0])
    assert cull.top_values[0] == pytest.approx(direct.value, rel=1e-12)
    for other in (values[best - 1], values[best + 1]):
        assert SG.velocity_gii(k, [other, 1, 1, other, 1, 1], [5, 5, 5, 30, 30]).value < direct.value


def test_no_design_reaches_the_workspace_at_10_cm(spec):
    study = _reduced(spec, 100.0, [1.0, 1.6])
    res = run_study(study, top_k=1)
    assert res.top_values[0] == -np.inf                              # reported as "no design reaches"


def test_fast_evaluator_equals_one_model_per_design(spec):
    """Adding a geometry entry to the grid forces the Generic evaluator; at the same design the
    per-sample singular values are the SensorOnly ones."""
    fast = _reduced(spec, 200.0, [1.2, 1.6])
    data = copy.deepcopy(fast.raw)
    data["grid"] = {"pen_length": [70.0, 90.0], "Q1": data["grid"]["Q1"]}
    slow = build_study(study_from_data(data, f"{KEY}.toml", KEY))
    ev_fast, ev_slow = make_evaluator(fast), make_evaluator(slow)
    assert type(ev_slow).__name__ == "Generic"
    samples = np.arange(fast.n_samples)
    a_f, b_f = ev_fast(np.array([1]), samples)                       # Q1 = 1.6
    a_s, b_s = ev_slow(np.array([1]), samples)                       # pen 70 mm, Q1 = 1.6
    assert np.allclose(a_f, a_s, rtol=1e-12) and np.allclose(b_f, b_s, rtol=1e-12)


BASE = """
[mechanism]
kind = "twin_pantograph"
[grid]
Q1 = { targets = ["gear_ratios.q1", "gear_ratios.q4"], values = [1.0, 1.6] }
[workspace]
kind = "points"
points = [[0.0, 0.0, 250.0]]
[workspace.orientations]
tip_bound = 45.0
rings = 1
[objective]
kind = "sensor_gii"
"""


@pytest.mark.parametrize("extra, key", [
    ('S_T = [5.0, 5.0, 30.0]', "objective.S_T"),
    ('S_T = "human_hand"', "objective.S_T"),
    ('threshold = 5.0', "objective.threshold"),
    ('frame = "tool"', "objective.frame"),
    ('\n[series]\nkey = "workspace.centre.z"\nvalues = [200.0, 250.0]\nparameters = { upper_arm = [170.0] }',
     "series.parameters.upper_arm"),
    ('\n[series]\nkey = "workspace.centre.z"\nvalues = [200.0]\nparameters = { wings = [1.0] }',
     "series.parameters.wings"),
    ('\n[series]\nkey = "workspace.centre.z"\nvalues = [200.0]\nparameters = { upper_arm = [-5.0] }',
     "series.parameters.upper_arm"),
])
def test_bad_keys_name_the_file_and_the_key(extra, key):
    with pytest.raises(StudyError) as info:
        build_study(parse_study_text(BASE + extra + "\n", "sensor_bad.toml"))
    msg = str(info.value)
    assert "sensor_bad.toml" in msg and f"key '{key}'" in msg


def test_numeric_velocities_are_used_as_given():
    spec = parse_study_text(BASE + "S_T = [5.0, 5.0, 5.0, 10.0, 10.0]\n", "sensor_ok.toml")
    study = build_study(spec)
    assert study.objective.s_t == (5.0, 5.0, 5.0, 10.0, 10.0) and study.objective.frame == "base"
