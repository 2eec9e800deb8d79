"""Paper 001's reference-point hypothesis (issue 23 sec. 1): ``scripts/reference_point.py``'s table.

The figures of the table in docs/reproduction.md ("Paper 001: the reference-point hypothesis"),
computed by the script's own functions. Coarse but sufficient, as the script: the studies' 3 x 5
x 3 positions x 18 tip directions (810 poses), no re-optimization. To keep this under ~15 s it
pins every force GII (Tables VII/VIII, 0.1 s each), every Table X / eq. 28 figure (home pose
only) and the sensor GII (Table IX, about 2 s each: a 251-ratio search) at three
(reading, distance) pairs; the script prints the rest.

Tolerances are derived from how the figures are computed and printed: a GII is a minimum over
the same 810 poses of a deterministic SVD ratio (bit-for-bit repeatable up to the LAPACK's
rounding, ~1e-13), pinned to half a unit of its 6th decimal; an optimal ratio R_w/R_s lies on
the search grid (step 0.01), pinned to half a step; resolutions to 0.5 nm or 5e-7 deg, levers to
5e-5 cm, masses to 0.05 g cm^2 (the pins carry 4 to 6 significant digits, the doc's table 3).
"""
from __future__ import annotations

import math

import pytest

from kinematics import TwinPantograph
from resources import load_preset
from scripts import reference_point as R

BY_KEY = {r.key: r for r in R.READINGS}
GII_TOL = 5e-7

#: Force GII of Table VIII's printed designs (15..40 cm) under each reading; nan: no reach.
FORCE = {
    "mid": (math.nan, 0.384918, 0.454081, 0.499174, 0.531036, 0.551611),
    "tip": (math.nan, 0.127594, 0.164219, 0.189335, 0.210401, 0.225341),
    "mid_2l6": (0.105785, 0.187859, 0.236125, 0.260609, 0.277785, 0.286381),
    "tip_2l6": (math.nan, math.nan, math.nan, math.nan, 0.078128, 0.110433),
    "mid_off": (0.266682, 0.362181, 0.417240, 0.441426, 0.459095, 0.471009),
    "mid_2l6_off": (0.122232, 0.204255, 0.248111, 0.256447, 0.263753, 0.271400),
}
#: Table X at home: resolution x, y, z (um), rx, rz (deg); levers rx/z, rz/x (cm); eq. 28 rx rx, rz rz (g cm^2).
TABLE_X = {
    "mid": ((73.997, 157.080, 76.341, 0.124931, 0.121134), (3.431336, 3.5), (2368.48, 2395.85)),
    "tip": ((150.891, 157.684, 151.559, 0.125444, 0.123506), (6.773311, 7.0), (4798.61, 4804.84)),
    "mid_2l6": ((74.805, 157.080, 76.474, 0.061855, 0.061229), (6.375370, 7.0), (9460.03, 9472.48)),
    "tip_2l6": ((150.891, 162.679, 151.496, 0.063820, 0.067674), (13.236364, 12.775002), (19009.00, 17388.99)),
    "mid_off": ((79.657, 170.813, 76.389, 0.125010, 0.130400), (3.440545, 3.5), (2809.30, 2219.16)),
    "mid_2l6_off": ((80.400, 163.946, 76.451, 0.061860, 0.065808), (6.452747, 7.0), (9864.12, 8794.78)),
}


def test_the_presets_and_studies_carry_the_adopted_reading():
    """The model's default is the original reading; paper 001's presets and studies carry the
    adopted one (``mid_2l6``: ``ujoint_lever = 1.0``), and every reading names its lever."""
    from resources import load_study

    p = TwinPantograph().params
    assert (p.ujoint_lever, p.reference_along, p.reference_offset) == (0.5, 0.0, 0.0)
    assert BY_KEY["mid"].params == {"ujoint_lever": 0.5}
    assert all("ujoint_lever" in r.params for r in R.READINGS)
    assert R.ADOPTED == "mid_2l6" and BY_KEY[R.ADOPTED].params == {"ujoint_lever": 1.0}
    for key in ("twin_pantograph", "twin_pantograph_prototype"):
        q = load_preset(key).mechanism.params
        assert (q.ujoint_lever, q.reference_along, q.reference_offset) == (1.0, 0.0, 0.0), key
    for key in ("twin_pantograph_distance", "twin_pantograph_sensor", "twin_pantograph_table7"):
        assert load_study(key).mechanism.params.ujoint_lever == 1.0, key


@pytest.mark.parametrize("key", list(FORCE))
def test_force_gii_tables_7_8(key):
    got = [R.force_gii(BY_KEY[key], d) for d in R.TABLE8_DESIGNS]
    for d, g, want in zip(R.TABLE8_DESIGNS, got, FORCE[key]):
        if math.isnan(want):
            assert math.isnan(g), (key, d, g)
        else:
            assert g == pytest.approx(want, abs=GII_TOL), (key, d)


def test_adopted_reading_reproduces_table_8():
    """``mid_2l6``: within 3.5 % of the paper from 20 to 40 cm, reaches at 15 cm (19 % high); the default
    is 1.9-2.1x the paper's and does not reach at 15 cm with the paper's l6 = 7 cm."""
    for d, want in zip(R.TABLE8_DESIGNS, FORCE["mid_2l6"]):
        ratio = want / R.TABLE8_GII[d]
        assert abs(ratio - 1) <= (0.20 if d == 15 else 0.035), (d, ratio)
    for d, want in zip(list(R.TABLE8_DESIGNS)[1:], FORCE["mid"][1:]):
        assert 1.88 <= want / R.TABLE8_GII[d] <= 2.12


@pytest.mark.parametrize("key, distance, ratio, gii", [
    ("mid_2l6", 20, 1.58, 0.185341), ("mid_2l6", 40, 1.63, 0.282379), ("mid", 25, 1.49, 0.130693)])
def test_sensor_gii_table_9(key, distance, ratio, gii):
    got_ratio, got_gii = R.sensor_gii(BY_KEY[key], distance)
    assert got_ratio == pytest.approx(ratio, abs=0.005)
    assert got_gii == pytest.approx(gii, abs=GII_TOL)


@pytest.mark.parametrize("key", list(TABLE_X))
def test_table_x_and_eq28(key):
    res, levers, mass = TABLE_X[key]
    tx = R.table_x(BY_KEY[key])
    got_res = [v * 1e6 for v in tx["resolution"][:3]] + [math.degrees(v) for v in tx["resolution"][3:]]
    assert got_res[:3] == pytest.approx(res[:3], abs=5e-4)
    assert got_res[3:] == pytest.approx(res[3:], abs=5e-7)
    assert [v * 100 for v in tx["levers"]] == pytest.approx(levers, abs=5e-5)
    assert tx["mass"][:2].tolist() == pytest.approx(mass, abs=0.05)


def test_offset_reading_gives_eq28_coupling():
    """A task point 15.3 mm off the axis gives eq. 28's y-rx coupling to within 20 % (-291 against -346
    g cm); on the axis the model has none."""
    assert R.table_x(BY_KEY["mid_off"])["mass"][2] == pytest.approx(-291.01, abs=0.05)
    assert abs(R.table_x(BY_KEY["mid"])["mass"][2]) < 0.1


def test_score_counts_reproduced_figures():
    rows = [R.Row("t", "a", 1.0, {"mid": 1.1, "tip": 1.2}), R.Row("t", "b", 2.0, {"mid": math.nan, "tip": 1.8}),
            R.Row("t", "c", 2.0, {"mid": 2.0, "tip": 2.0}, scored=False)]
    readings = (BY_KEY["mid"], BY_KEY["tip"])
    assert R.score(rows, readings) == {"mid": 1, "tip": 1}


@pytest.mark.parametrize("kwargs", [
    {"ujoint_lever": 1.0}, {"reference_along": -1.0}, {"reference_offset": -0.0153},
    {"ujoint_lever": 1.0, "reference_along": 0.5, "reference_offset": 0.01, "redundant_waist": "passive"},
    {"ujoint_lever": 1.0, "reference_along": -1.0, "reference_offset": 0.01, "roll_actuator": "active",
     "redundant_waist": "passive"}])
def test_readings_round_trip_and_jacobian(kwargs):
    """FK(IK(x)) = x, and K matches central differences of the IK (through the coordinate rates)."""
    import numpy as np

    mech = TwinPantograph(**kwargs)
    rng = np.random.default_rng(3)
    m = mech.task_dim
    x = mech.home_pose(0.25) + np.concatenate([rng.normal(0, 0.01, (4, 3)), rng.normal(0, 0.3, (4, m - 3))], -1)
    q, ok = mech.inverse(x)
    assert ok.all()
    xf, okf = mech.forward(q)
    assert okf.all() and np.allclose(xf, x, rtol=0.0, atol=1e-12)
    tips = mech._config(x).tips                                        # the U-joints stay 2 h apart
    assert np.allclose(np.linalg.norm(tips[:, 1] - tips[:, 0], axis=-1), 2 * mech.half_span)
    eps = 1e-6
    for i in range(len(x)):
        k = mech.inverse_jacobian(q[i], x[i]) @ mech.coordinate_rates_to_twist(x[i])
        num = np.stack([(mech.inverse(x[i] + eps * e)[0] - mech.inverse(x[i] - eps * e)[0]) / (2 * eps)
                        for e in np.eye(m)], -1)
        assert np.allclose(k, num, rtol=0.0, atol=1e-7 * max(1.0, np.abs(num).max()))


def test_reading_geometry_and_batch_guard():
    import numpy as np

    from metrics.design import twin_batch

    mech = TwinPantograph(ujoint_lever=1.0, reference_along=-1.0)
    x = mech.home_pose(0.2)
    cfg = mech._config(x)
    assert np.allclose(cfg.tips[0], [0.0, 0.0, 0.2])                  # the task point is unit A's U-joint
    assert np.allclose(cfg.tips[1], [0.0, 2 * 0.07, 0.2])              # 2 l6 away
    assert mech.characteristic_length == pytest.approx(0.07)
    assert twin_batch.midpoint_reading(TwinPantograph())
    assert twin_batch.midpoint_reading(TwinPantograph(ujoint_lever=1.0))      # the batch takes any lever
    assert not twin_batch.midpoint_reading(mech)
    with pytest.raises(ValueError, match="midpoint"):
        twin_batch.force_gii_values(mech, {}, x[None], s_t=(1, 1, 1.5, 0.036, 0.039))
    with pytest.raises(ValueError):
        TwinPantograph(ujoint_lever=0.0)
    with pytest.raises(ValueError):
        TwinPantograph(reference_offset=float("nan"))
