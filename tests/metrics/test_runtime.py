"""Run time predicted before a map starts (metrics.runtime): rules tested with injected rates and clocks.

Before: ``isoforce stats novint_falcon --resolution 1000000`` (10^18 points) started as readily
as a second's job. No test here depends on the machine's speed.
"""
from __future__ import annotations

import math

import pytest

from metrics.budget import CHUNK_POINTS
from metrics.quantities import STATS_QUANTITIES
from metrics.runtime import (
    MAX_SECONDS,
    MIN_SAMPLE,
    SAMPLE_POINTS,
    UNTIMED_POINTS,
    Prediction,
    RunTimeError,
    check_run_time,
    format_duration,
    largest_within,
    sample_points,
    seconds_per_point,
)
from metrics.workspace import sample_grid
from resources import load_preset


@pytest.mark.parametrize("seconds, text", [
    (1e-9, "1 ns"), (4.2e-5, "42 µs"), (0.5, "500 ms"), (42.0, "42 s"), (90.0, "1.5 min"), (3600.0, "1 h"),
    (86400.0 * 3, "3 days"), (1e12, "31,700 years"), (math.inf, "forever"),
])
def test_durations_read_as_a_person_writes_them(seconds, text):
    assert format_duration(seconds) == text


@pytest.mark.parametrize("rate, k, limit", [(1e-6, 2, 3600.0), (7.3e-5, 3, 3600.0), (2.5e-4, 2, 1.0),
                                            (1e-9, 3, 1e6)])
def test_the_largest_resolution_is_the_last_that_fits(rate, k, limit):
    def seconds_at(n):
        return rate * n ** k

    n = largest_within(seconds_at, limit)
    assert seconds_at(n) <= limit < seconds_at(n + 1)         # brute force around the bisection


def test_a_long_job_is_refused_with_its_prediction_and_the_largest_resolution():
    rate = 8e-6                                  # injected: s per point
    points = 8000 ** 3
    with pytest.raises(RunTimeError) as info:
        check_run_time("a 8000 x 8000 x 8000 map", points, points * rate, seconds_at=lambda n: rate * n ** 3)
    text = str(info.value)
    assert 766 ** 3 * rate <= MAX_SECONDS < 767 ** 3 * rate          # 3595.6 s and 3609.7 s
    assert "would take about 47 days" in text and "512,000,000,000 points at 8 µs each" in text
    assert "the largest that finishes within 1 h is --resolution 766 (about 60 min)" in text
    assert "--max-time SECONDS allows longer" in text and "\n" not in text


def test_a_limit_below_the_smallest_grid_says_so():
    with pytest.raises(RunTimeError, match=r"no --resolution finishes within 1 ns \(--resolution 2 takes about 4 µs\)"):
        check_run_time("a map", 10 ** 10, 1e4, seconds_at=lambda n: 1e-6 * n * n, max_seconds=1e-9)


def test_a_job_within_the_limit_gets_its_prediction():
    p = check_run_time("a map", 10 ** 6, 3599.0, seconds_at=lambda n: 0.0)
    assert p == Prediction(10 ** 6, 3599.0) and p.seconds_per_point == 3599.0 / 10 ** 6


def test_the_rate_is_the_slope_between_two_samples_plus_the_call_over_a_chunk():
    """A fake clock, read at each timed map's start and after its last chunk, nowhere else: the
    smaller sample grid twice (the faster counts), then the larger twice (likewise). The per-point
    time is the slope between them; the rest of the smaller's time, the call's own cost, comes back
    spread over a full chunk's points."""
    preset = load_preset("fivebar_singh")
    grid = preset.grid.with_resolution(10 ** 6)
    readings = iter([0.0, 0.011, 1.0, 1.010, 100.0, 100.025, 200.0, 200.022])
    rate = seconds_per_point(preset.mechanism, grid, STATS_QUANTITIES, sample=SAMPLE_POINTS,
                             clock=lambda: next(readings))
    assert sample_grid(grid, SAMPLE_POINTS // 2).resolution == (128, 128)
    assert sample_grid(grid, SAMPLE_POINTS // 8).resolution == (64, 64)
    slope = (0.022 - 0.010) / (128 * 128 - 64 * 64)
    assert rate == pytest.approx(slope + (0.010 - slope * 64 * 64) / CHUNK_POINTS, rel=1e-9)


def test_a_larger_sample_no_slower_than_the_smaller_is_taken_whole():
    """Noise can make the larger sample no slower than the smaller: then its whole time over its
    points, never a rate of 0 or below."""
    preset = load_preset("fivebar_singh")
    grid = preset.grid.with_resolution(10 ** 6)
    readings = iter([0.0, 0.5, 1.0, 1.5, 2.0, 2.25, 3.0, 3.25])
    rate = seconds_per_point(preset.mechanism, grid, STATS_QUANTITIES, sample=8192, clock=lambda: next(readings))
    assert sample_grid(grid, 4096).resolution == (64, 64)
    assert rate == pytest.approx(0.25 / (64 * 64), rel=1e-12)


@pytest.mark.parametrize("points, sample", [(UNTIMED_POINTS + 1, MIN_SAMPLE), (32 * MIN_SAMPLE, MIN_SAMPLE),
                                            (32 * 20000, 20000), (32 * SAMPLE_POINTS, SAMPLE_POINTS),
                                            (10 ** 18, SAMPLE_POINTS)])
def test_a_sample_is_a_32nd_of_the_job_within_its_bounds(points, sample):
    assert sample_points(points) == sample
