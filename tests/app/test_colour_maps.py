"""The numpy floor's colour tables and ticks against matplotlib, their source.

``app.logic`` colours and ticks the app's map without matplotlib; the exported figures use
matplotlib. Both must agree exactly: the tables entry by entry, the ticks over many ranges.
"""
from __future__ import annotations

import numpy as np
import pytest
from matplotlib import colormaps, colors, ticker

from app.logic.colour_maps import TABLES, colour_table
from app.logic.colour_scale import BOTTLENECK_CODES, hex_rgba
from app.logic.ticks import AXIS_STEPS, nice_ticks


@pytest.mark.parametrize("name", sorted(TABLES))
def test_each_table_is_matplotlibs_colour_map(name):
    cmap = colormaps[name]
    np.testing.assert_array_equal(colour_table(name), cmap(np.arange(cmap.N)))
    np.testing.assert_array_equal((colour_table(name) * 255).astype(np.uint8), cmap(np.arange(cmap.N), bytes=True))


def test_hex_colours_read_as_matplotlib_reads_them():
    for _, colour in BOTTLENECK_CODES.values():
        assert hex_rgba(colour) == colors.to_rgba(colour)


def test_an_unknown_table_is_refused_by_name():
    with pytest.raises(ValueError, match="name must be one of"):
        colour_table("jet")


def test_nice_ticks_are_matplotlibs_max_n_locator():
    """Ranges from 1e-8 to 1e8 wide, centred at 0 or far off it (matplotlib's offset branch)."""
    rng = np.random.default_rng(7)
    for _ in range(3000):
        centre = rng.choice([0.0, 1.0, -50.0, 1e3, 1e6, 1e-6])
        width = 10 ** rng.uniform(-8, 8)
        lo = centre + rng.uniform(-1, 1) * width
        hi = lo + width * rng.uniform(0.01, 3)
        nbins = int(rng.integers(2, 10))
        want = ticker.MaxNLocator(nbins=nbins, steps=list(AXIS_STEPS)).tick_values(lo, hi)
        np.testing.assert_array_equal(nice_ticks(lo, hi, nbins), want, err_msg=f"{lo!r}, {hi!r}, {nbins}")


def test_nice_ticks_of_an_empty_range_are_matplotlibs():
    for lo in (0.0, 1.0, -3e5):
        want = ticker.MaxNLocator(nbins=5, steps=list(AXIS_STEPS)).tick_values(lo, lo)
        np.testing.assert_array_equal(nice_ticks(lo, lo, 5), want)
