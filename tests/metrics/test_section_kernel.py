"""``kernels.section`` (``wrench_slices.slice_max_norm``) against the numpy passes it replaced.

The kernel does numpy's operations in numpy's order on every value that can reach the result
(``kernels/section.py``), and what it skips (a candidate's image once it is outside the box) never
entered the maximum: the same bits are the derived tolerance. The reference is the numpy code
kept in ``reference_kernels.slice_max_norm_section``.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest
import reference_kernels as ref

from metrics import wrench_slices
from resources import load_preset


def _slices(m):
    """Every slice a shape takes: 1 to 3 other rows, at least one slice row."""
    return [rows for d in range(max(1, m - 3), m) for rows in itertools.combinations(range(m), d)]


def _same(gens, rows):
    with np.errstate(all="ignore"):
        want = ref.slice_max_norm_section(gens, rows=rows)
    np.testing.assert_array_equal(wrench_slices.slice_max_norm(gens, rows=rows), want)


@pytest.mark.parametrize("m, n", [(2, 2), (3, 3), (3, 5), (4, 6), (5, 6), (6, 6), (6, 9)])
def test_random_generators_give_the_numpy_bits(m, n):
    rng = np.random.default_rng(100 * m + n)
    gens = rng.normal(size=(300, m, n)) * np.exp(rng.normal(scale=3.0, size=(300, 1, n)))
    for rows in _slices(m):
        _same(gens, rows)


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e150, 1e300])
def test_extreme_scales_give_the_numpy_bits(scale):
    rng = np.random.default_rng(7)
    gens = rng.normal(size=(200, 6, 6)) * scale
    for rows in ([0, 1, 2], [3, 4, 5], [0, 4, 5, 1]):
        _same(gens, rows)


def test_degenerate_and_bad_generators_give_the_numpy_bits_and_labels():
    """Repeated and opposite columns (free sets singular within rounding), zero rows and columns,
    non-finite entries, rank-deficient ``G_O``: numpy's values, ``nan`` where it has ``nan``."""
    rng = np.random.default_rng(11)
    gens = rng.normal(size=(240, 6, 6))
    gens[0:40, :, 1] = gens[0:40, :, 0]                      # identical generators
    gens[40:80, :, 2] = -gens[40:80, :, 3]                   # opposite
    gens[80:100, 3:, :] = 0.0                                # G_O = 0: no candidate, nan
    gens[100:120, :, 4] = 0.0                                # a dead actuator
    gens[120:140, 4, :] = gens[120:140, 3, :]                # G_O of rank 2
    gens[140, 2, 2] = np.nan
    gens[141, 0, 5] = np.inf
    gens[142:160, :3, :] = 0.0                               # the slice rows all 0: size 1, norm 0
    gens[160:200] = np.round(gens[160:200])                  # small integers: exact zeros in minors
    for rows in _slices(6):
        _same(gens, rows)
    out = wrench_slices.slice_max_norm(gens, rows=[0, 1, 2])
    assert np.isnan(out[140]) and np.isnan(out[141]) and np.all(np.isnan(out[80:100]))


def test_square_other_rows_leave_only_the_origin():
    """``n = r`` (``G_O`` square, no fixed generator): the section is ``s = 0``, the norm 0 where
    ``det G_O`` is nonzero; numpy's bits either way."""
    rng = np.random.default_rng(5)
    gens = rng.normal(size=(50, 4, 3))
    gens[:10, 1:, 0] = 0.0                                   # det G_O = 0: no candidate
    _same(gens, [0])
    out = wrench_slices.slice_max_norm(gens, rows=[0])
    assert np.all(out[10:] == 0.0) and np.all(np.isnan(out[:10]))


def test_batch_axes_and_empty_batches():
    rng = np.random.default_rng(3)
    gens = rng.normal(size=(4, 5, 6, 6))
    _same(gens, [0, 1, 2])
    assert wrench_slices.slice_max_norm(gens, rows=[0, 1, 2]).shape == (4, 5)
    assert wrench_slices.slice_max_norm(np.zeros((0, 6, 6)), rows=[0, 1, 2]).shape == (0,)


def test_the_input_is_left_alone_and_points_are_independent():
    """The kernel overwrites its own copy, never the caller's array; a point's value does not
    depend on its neighbours (the numpy blocks' boundaries are gone)."""
    rng = np.random.default_rng(9)
    gens = rng.normal(size=(64, 6, 6))
    before = gens.copy()
    whole = wrench_slices.slice_max_norm(gens, rows=[3, 4, 5])
    np.testing.assert_array_equal(gens, before)
    parts = [wrench_slices.slice_max_norm(gens[i:i + 5], rows=[3, 4, 5]) for i in range(0, 64, 5)]
    np.testing.assert_array_equal(np.concatenate(parts), whole)


@pytest.mark.parametrize("key", ["stewart_platform", "inoue_platform", "twin_pantograph_prototype"])
def test_shipped_devices_give_the_numpy_bits(key):
    preset = load_preset(key)
    mech = preset.mechanism
    pts = preset.grid.points(mech.task_names)[::9]
    q, ok = mech.inverse(pts)
    keep = ok & mech.feasible(q, pts)
    gens = mech.force_map(q[keep], pts[keep]) * mech.torque_limits()
    assert len(gens) > 100
    for rows in ([0, 1, 2], [3, 4, 5]) if gens.shape[-2] == 6 else ([0, 1, 2], [3, 4]):
        _same(gens, rows)


def test_load_pieces_loads_once_and_counts_its_time():
    from metrics import kernels, runtime

    before = kernels.compile_seconds()
    took = runtime.load_pieces()
    assert kernels.compile_seconds() == before + took
    assert runtime.load_pieces() == 0.0
