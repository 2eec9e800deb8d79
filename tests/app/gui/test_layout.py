"""The window's layout (issue 11 sec. 1): the map is the largest view, nothing of it clipped or
over the data, the device list shows names, empty parameter groups are hidden, and errors
come in one dialog at a time."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import shrink_grid, wait_full_map
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PySide6.QtWidgets import QGroupBox, QMessageBox

from app.figures import map_figure
from metrics.workspace import compute_map
from resources import list_presets, load_preset


@pytest.mark.parametrize("size", [(1600, 950), (1920, 1080)])
@pytest.mark.parametrize("device", ["inverse3_prototype", "fivebar_singh"])
def test_the_map_is_the_largest_view_and_nothing_of_it_is_clipped(make_window, qtbot, size, device):
    window = make_window(device, longest=60)
    window.resize(*size)
    qtbot.waitUntil(lambda: window.width() == size[0], timeout=5000)
    wait_full_map(qtbot, window)
    window.map_view.canvas.draw()
    map_area = window.map_view.width() * window.map_view.height()
    for other in (window.tabs, window.param_dock, window.stats_dock):
        assert map_area > other.width() * other.height(), other.objectName()
    fig = window.map_view.figure
    renderer = window.map_view.canvas.get_renderer()
    canvas_box = fig.bbox
    ax = window.map_view._axes[0]
    for artist in (ax.title, ax.get_legend(), window.map_view._artists[0]["colorbar"].ax):
        box = artist.get_window_extent(renderer)
        # Inside the canvas (a pixel of rounding allowed): no title or legend cut at its edge.
        assert box.x0 >= canvas_box.x0 - 1 and box.x1 <= canvas_box.x1 + 1
        assert box.y0 >= canvas_box.y0 - 1 and box.y1 <= canvas_box.y1 + 1
    # The legend of extremes is not over the data: it lies wholly below the axes.
    assert ax.get_legend().get_window_extent(renderer).y1 <= ax.bbox.y0
    # The colour bar's label is no taller than its bar.
    bar = window.map_view._artists[0]["colorbar"]
    assert bar.ax.yaxis.label.get_window_extent(renderer).height <= bar.ax.bbox.height + 1


def test_an_exported_map_has_its_legend_off_the_data_too():
    preset = load_preset("fivebar_singh")
    wmap = compute_map(preset.mechanism, shrink_grid(preset.grid, 60), ("isotropic_force",))
    fig = map_figure(wmap, "isotropic_force", preset)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    assert legend.y1 <= ax.bbox.y0 and legend.y0 >= fig.bbox.y0 - 1


def test_the_device_list_shows_names_and_chooses_by_key(make_window, qtbot):
    window = make_window("fivebar_singh", longest=40)
    box = window.param_panel.preset_box
    keys = [box.itemData(i) for i in range(box.count())]
    assert keys == list_presets()
    assert [box.itemText(i) for i in range(box.count())] == [load_preset(k).name for k in keys]
    assert box.currentText() == "Five-bar (Singh et al.)" and box.currentData() == "fivebar_singh"
    with qtbot.waitSignal(window.param_panel.presetChosen) as blocker:
        box.activated.emit(keys.index("woodenhaptics"))
    assert blocker.args == ["woodenhaptics"]
    wait_full_map(qtbot, window)
    assert window.state.preset.key == "woodenhaptics" and box.currentData() == "woodenhaptics"


@pytest.mark.parametrize("device", ["fivebar_singh", "inverse3_prototype", "haply_2diy"])
def test_a_parameter_group_is_shown_only_with_rows_in_it(make_window, device):
    window = make_window(device, longest=40)
    groups = window.param_panel.body.findChildren(QGroupBox)
    assert groups
    for group in groups:
        assert group.isVisibleTo(window.param_panel) == (group.layout().rowCount() > 0), group.title()


def test_errors_come_in_one_dialog_at_a_time(make_window):
    window = make_window("fivebar_singh", longest=40)
    window.show_error("first failure")
    first = window.error_box
    window.show_error("first failure")
    window.show_error("second failure")
    boxes = [w for w in window.findChildren(QMessageBox) if w.isVisible()]
    assert boxes == [first] and first.text() == "second failure"
    first.close()
    window.show_error("third failure")          # closed: the next error opens a dialog again
    assert window.error_box is not first and window.error_box.isVisible()
    assert window.error_box.text() == "third failure"


@pytest.mark.parametrize("quantity", ["isotropic_force", "condition_number"])
def test_the_map_on_screen_and_the_exported_figure_show_the_same_data_and_colours(make_window, qtbot, quantity):
    window = make_window("fivebar_singh", longest=60)
    window.quantity_box.setCurrentIndex(window.quantity_box.findData(quantity))
    qtbot.waitUntil(lambda: window.state.current is not None and quantity in window.state.current.map.values
                    and window.state.current.stage == "full" and not window.state.busy, timeout=30_000)
    st = window.state
    screen = window.map_view.figure.axes[0].images[0]
    exported = map_figure(st.current.map, quantity, st.preset).axes[0].images[0]
    a, b = screen.get_array(), exported.get_array()
    np.testing.assert_array_equal(np.ma.getmaskarray(a), np.ma.getmaskarray(b))
    np.testing.assert_array_equal(np.ma.getdata(a)[~np.ma.getmaskarray(a)], np.ma.getdata(b)[~np.ma.getmaskarray(b)])
    assert screen.get_clim() == exported.get_clim()
    assert type(screen.norm) is type(exported.norm)
    levels = np.linspace(0.0, 1.0, 256)
    np.testing.assert_array_equal(screen.cmap(levels), exported.cmap(levels))     # the same lookup table
