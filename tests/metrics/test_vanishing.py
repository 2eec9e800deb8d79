"""Infima that are 0 in truth (metrics.suprema.VANISHING_NEAR): the grid's smallest value is not the minimum."""
from __future__ import annotations

import numpy as np

from metrics.quantities import evaluate
from metrics.workspace import compute_map
from resources import load_preset


def test_falcon_isotropic_force_vanishes_at_its_direct_singularity():
    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid.with_resolution(21), ("isotropic_force", "inverse_condition_number"),
                       keep=False)
    iso = wmap.stats["isotropic_force"]
    assert iso.vanishes and iso.min == 0.0 and iso.vanishes_at
    assert wmap.errors["isotropic_force"]["min"] == 0.0
    assert iso.as_dict()["vanishes"] is True
    # In truth: approaching a direct locus point the isotropic force falls towards 0 (J -> inf).
    p = np.array(iso.vanishes_at[0])
    start = np.array(preset.pose)
    values = [evaluate(mech, (p + gap * (start - p))[None], ("isotropic_force",)).values["isotropic_force"][0]
              for gap in (1e-2, 1e-4)]
    assert np.all(np.isfinite(values)) and values[1] < 0.5 * values[0]


def test_a_mechanism_without_singular_loci_keeps_its_grid_minimum():
    preset = load_preset("inverse3_prototype")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(60), ("isotropic_force",), keep=False)
    iso = wmap.stats["isotropic_force"]
    assert not iso.vanishes and iso.min > 0


def test_five_bar_inverse_condition_number_vanishes_where_its_condition_number_is_unbounded():
    preset = load_preset("fivebar_singh")
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(60),
                       ("condition_number", "inverse_condition_number"), keep=False)
    assert wmap.stats["condition_number"].unbounded
    assert wmap.stats["inverse_condition_number"].vanishes
    assert wmap.stats["inverse_condition_number"].min == 0.0
