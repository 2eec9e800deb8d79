"""The statistics panel shows a gear ratio's force gain and its mass cost together (issue 22, sec. 5):
apparent masses and isotropic acceleration beside the forces for a device with a mass model, with
their change against a pinned reference; none for a device without bodies."""
from __future__ import annotations

from conftest import wait_full_map, wait_reference_map

from metrics.quantities import DYNAMIC_SUMMARY
from metrics.workspace import compute_map
from tests.preset_files import massless_omni


def test_a_gear_ratio_shows_its_force_gain_and_its_apparent_mass_cost_against_the_reference(make_window, qtbot):
    window = make_window("inverse3_prototype", longest=40)
    st, panel = window.state, window.stats_panel
    wait_full_map(qtbot, window)
    for q in DYNAMIC_SUMMARY:
        assert q in st.current.map.stats
    # The panel's figure is the map's statistic (computed independently here).
    own = compute_map(st.mechanism, st.preset.grid, DYNAMIC_SUMMARY)
    text = panel.cell("apparent_mass_max", "mean", 1).split()[0]
    # Printed to the digits its grid error allows: equal to within half its last digit.
    decimals = len(text.split(".")[1]) if "." in text else 0
    assert abs(float(text) - own.stats["apparent_mass_max"].mean) <= 0.5 * 10.0**-decimals
    window.pin_reference()
    wait_reference_map(qtbot, window)
    ratios = st.mechanism.params.gear_ratios
    window.on_parameter_edited("gear_ratios", (2 * ratios[0], *ratios[1:]), False)
    qtbot.waitUntil(lambda: st.current.mechanism.params.gear_ratios[0] == 2 * ratios[0]
                    and st.current.stage == "full", timeout=60_000)
    qtbot.waitUntil(lambda: panel.cell("apparent_mass_max", "mean", 4) not in ("", "-"), timeout=10_000)
    # Twice the base ratio: four times its rotor's J N^2, so the heaviest direction gets heavier,
    # and the isotropic force does not fall.
    assert panel.cell("apparent_mass_max", "mean", 4).startswith("+")
    assert not panel.cell("isotropic_force", "mean", 4).startswith("-")



def test_a_device_without_a_mass_model_has_no_mass_rows(make_window, qtbot, tmp_path):
    window = make_window(massless_omni(tmp_path), longest=40)
    wait_full_map(qtbot, window)
    assert not any(q in window.state.current.map.stats for q in DYNAMIC_SUMMARY)
    assert not any(key[0] in DYNAMIC_SUMMARY for key in window.stats_panel.rows)
