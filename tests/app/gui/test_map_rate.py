"""``app.gui.map_rate``: measured map rates and the predictions a slider step is planned from (no Qt)."""
from __future__ import annotations

import math

import pytest

from app.gui.map_rate import FRAME_S, KEPT, MapRates, rate_key
from kinematics.fivebar import FiveBar

KEY = ("Model", ("isotropic_force",))


def test_a_kind_never_measured_has_no_prediction_and_is_never_within_a_frame():
    rates = MapRates()
    assert rates.seconds(KEY, 100) is None and rates.points_per_second(KEY) is None
    assert not rates.within_frame(KEY, 1)
    rates.add(("Other", ()), 100, 1e-6)             # another kind says nothing of this one
    assert rates.seconds(KEY, 100) is None


def test_at_a_measured_size_the_prediction_is_the_median_of_the_last_times():
    rates = MapRates()
    times = [0.010, 0.030, 0.020, 0.050]
    for t in times:
        rates.add(KEY, 400, t)
    last = sorted(times[-KEPT:])
    assert rates.seconds(KEY, 400) == last[len(last) // 2]          # KEPT = 3: the middle one


def test_another_size_is_predicted_at_the_median_rate_of_the_last_maps():
    rates = MapRates()
    rates.add(KEY, 100, 0.01)           # 1e4 points/s
    rates.add(KEY, 1000, 0.05)          # 2e4 points/s
    assert rates.seconds(KEY, 5000) == pytest.approx(5000 / 1.5e4, rel=1e-15)      # (median of two: their mean)
    rates.add(KEY, 1000, 0.025)         # 4e4 points/s
    assert rates.points_per_second(KEY) == pytest.approx(2e4, rel=1e-15)
    assert rates.seconds(KEY, 5000) == pytest.approx(0.25, rel=1e-15)


def test_one_slow_map_is_forgotten_after_the_next_ones():
    rates = MapRates()
    rates.add(KEY, 14_400, 1.0)         # a cold start
    for _ in range(KEPT - 1):
        rates.add(KEY, 1024, 1024 / 3e5)
    assert rates.points_per_second(KEY) == pytest.approx(3e5, rel=1e-12)


@pytest.mark.parametrize("fixed_s, per_point_s, measured, asked", [
    (0.01, 1e-6, (10_000,), 1_000_000), (0.002, 4e-7, (1024, 14_400, 3600), 135_981), (0.0, 1e-6, (500, 20), 501)])
def test_a_larger_map_is_never_predicted_faster_than_a_fixed_plus_per_point_cost(fixed_s, per_point_s,
                                                                                 measured, asked):
    # t(N) = a + b N with a >= 0, measured at each N_i <= N2 and predicted at N2 by proportion:
    # N2 (a + b N_i) / N_i = a N2 / N_i + b N2 >= a + b N2 for every i, so for their median rate
    # too. A map that would miss its frame is not taken for one that makes it.
    rates = MapRates()
    for n in measured:
        rates.add(KEY, n, fixed_s + per_point_s * n)
    assert rates.seconds(KEY, asked) >= (fixed_s + per_point_s * asked) * (1 - 1e-12)


def test_within_a_frame_compares_the_prediction_with_the_frame():
    rates = MapRates()
    rates.add(KEY, 1000, FRAME_S)
    assert rates.within_frame(KEY, 1000)                 # at the frame: within it
    assert not rates.within_frame(KEY, 1001)             # one point more at the same rate: past it
    assert rates.within_frame(KEY, 2000, frame_s=2 * FRAME_S)


@pytest.mark.parametrize("seconds", [0.0, -1.0, math.nan])
def test_a_time_that_says_nothing_of_a_rate_is_not_recorded(seconds):
    rates = MapRates()
    rates.add(KEY, 100, seconds)
    rates.add(KEY, 0, 0.01)
    assert rates.points_per_second(KEY) is None


def test_the_key_is_the_model_and_the_set_of_quantities():
    a, b = FiveBar(), FiveBar().replace_display(proximal=120.0)
    assert rate_key(a, ("isotropic_force", "condition_number")) == rate_key(b, ("condition_number", "isotropic_force"))
    assert rate_key(a, ("isotropic_force",)) != rate_key(a, ("isotropic_force", "condition_number"))


def test_a_map_on_one_core_is_a_kind_of_its_own():
    """A preview (one core, in the map worker process) predicts no full map (over the cores)."""
    a = FiveBar()
    one_core, cores = rate_key(a, ("isotropic_force",), threads=False), rate_key(a, ("isotropic_force",))
    assert one_core != cores and cores == rate_key(a, ("isotropic_force",), threads=True)
    rates = MapRates()
    rates.add(one_core, 14_400, 0.003)
    assert rates.seconds(cores, 10**6) is None and rates.seconds(one_core, 14_400) == 0.003


def test_measured_says_whether_a_size_was_timed_not_extrapolated():
    rates = MapRates()
    rates.add(KEY, 1000, 0.01)
    assert rates.measured(KEY, 1000) == 1 and rates.measured(KEY, 2000) == rates.measured(("Other", ()), 1000) == 0
    assert rates.seconds(KEY, 2000) is not None          # (extrapolated)
    for _ in range(KEPT + 1):
        rates.add(KEY, 1000, 0.01)
    assert rates.measured(KEY, 1000) == KEPT             # (the last KEPT)


def test_a_time_recorded_as_a_bound_is_marked_while_it_is_kept():
    """``bounded`` while any kept time is a lower bound (the median may be one), not only the last:
    two bounds and one whole time still predict from a bound."""
    rates = MapRates()
    rates.add(KEY, 1000, 0.01)
    rates.add(KEY, 1000, 0.05, bound=True)         # stopped unfinished after 50 ms
    assert rates.bounded(KEY, 1000) and not rates.bounded(KEY, 2000)
    assert rates.seconds(KEY, 1000) == pytest.approx(0.03, rel=1e-15)    # (a median of two: their mean)
    rates.add(KEY, 1000, 0.05, bound=True)
    rates.add(KEY, 1000, 0.02)                     # kept: 0.05 (bound), 0.05 (bound), 0.02
    assert rates.bounded(KEY, 1000) and rates.seconds(KEY, 1000) == 0.05
    for _ in range(KEPT - 1):                      # whole times push the bounds out
        assert rates.bounded(KEY, 1000)
        rates.add(KEY, 1000, 0.02)
    assert not rates.bounded(KEY, 1000)
