"""``isoforce stats``'s text: one formatting rule with the app (digits to the error, display
units), coordinates without rounding residue, and figures the grid does not resolve marked."""
from __future__ import annotations

import re

import pytest

from app.cli import main
from app.cli._format import point_text, with_error
from app.logic.figure_digits import format_with_error, unresolved
from resources import load_preset


def test_a_figure_keeps_the_digits_its_error_supports():
    # Before: "2.27969 +- 0.003" (six digits against an error in the third decimal).
    assert with_error(2.27969, 0.003) == "2.280 +- 0.003"
    assert with_error(2.27969, 0.003) == " +- ".join(format_with_error(2.27969, 0.003))


def test_an_error_at_least_the_figure_is_marked_unresolved():
    assert with_error(3e-06, 7e-06).endswith("(unresolved)")
    assert not with_error(2.28, 0.003).endswith("(unresolved)")
    assert unresolved(-1.0, 1.0) and not unresolved(1.0, float("nan")) and not unresolved(0.0, 0.0)


def test_coordinates_print_without_rounding_residue():
    mech = load_preset("inverse3_prototype").mechanism
    # Before: "(2.834e-07, 0, 278.6) mm".
    assert point_text(mech, [2.834e-10, -1e-12, 0.2786]) == "(0, 0, 278.6) mm"
    assert point_text(mech, [0.0123456, 0.0, 0.1]) == "(12.346, 0, 100) mm"


@pytest.fixture(scope="module")
def stats_text():
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["stats", "inverse3_prototype", "--resolution", "60"]) == 0
    return out.getvalue()


def test_the_spatial_resolution_row_is_in_micrometres_as_in_the_app_and_spec(stats_text):
    row = next(line for line in stats_text.splitlines() if line.startswith("spatial_resolution"))
    assert row.split()[1] == "µm"
    # Its median is tens of micrometres on this device, not 8.6e-05.
    median = float(row.split()[8])          # quantity, unit, min +- e, p05 +- e, median
    assert 10.0 < median < 500.0


def test_every_figure_in_the_table_has_no_more_digits_than_its_error(stats_text):
    for line in stats_text.splitlines():
        for value, error in re.findall(r"(-?[\d.]+(?:e[+-]\d+)?) \+- ([\d.]+(?:e[+-]\d+)?)", line):
            v_places = len(value.split("e")[0].split(".")[1]) if "." in value.split("e")[0] else 0
            e_places = len(error.split("e")[0].split(".")[1]) if "." in error.split("e")[0] else 0
            assert v_places == e_places, line
