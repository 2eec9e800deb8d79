"""The window's layout (issue 11 sec. 1): the map is the largest view, nothing of it clipped or
over the data, the device list shows names, empty parameter groups are hidden, and errors
come in one dialog at a time."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import shrink_grid, wait_full_map, widget_rgb
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PySide6.QtCore import QRectF
from PySide6.QtGui import QFontMetricsF
from PySide6.QtWidgets import QGroupBox, QLabel, QMessageBox

from app.logic.map_picture import colour_samples
from app.plots.figures import map_figure, matplotlib_norm
from metrics.workspace import compute_map
from resources import list_presets, load_preset


@pytest.mark.parametrize("size", [(1600, 950), (1920, 1080)])
@pytest.mark.parametrize("device", ["inverse3_prototype", "fivebar_singh"])
def test_the_map_is_the_largest_view_and_nothing_of_it_is_clipped(make_window, qtbot, size, device):
    window = make_window(device, longest=60)
    window.resize(*size)
    qtbot.waitUntil(lambda: window.width() == size[0], timeout=5000)
    wait_full_map(qtbot, window)
    map_area = window.map_view.width() * window.map_view.height()
    for other in (window.tabs, window.param_dock, window.stats_dock):
        assert map_area > other.width() * other.height(), other.objectName()
    canvas = window.map_view.canvas
    inside = QRectF(canvas.rect()).adjusted(-1, -1, 1, 1)       # a pixel of rounding allowed
    (lay,) = canvas.layouts
    # Inside the canvas: no title, legend, axes or colour bar cut at its edge.
    for name, rect in (("title", lay.title), ("legend", lay.legend), ("axes", lay.axes), ("bar", canvas.bar_rect)):
        assert inside.contains(rect), (name, rect, canvas.rect())
    # The texts fit their regions: the title's lines above the axes, the legend's rows below them.
    panel = window.map_view.picture.panels[0]
    title_fm, small_fm = QFontMetricsF(canvas.title_font), QFontMetricsF(canvas.small_font)
    assert lay.title.height() >= title_fm.lineSpacing() * (panel.title.count("\n") + 1)
    assert max(title_fm.horizontalAdvance(t) for t in panel.title.split("\n")) <= lay.title.width()
    # The legend of extremes is not over the data: it lies wholly below the axes.
    assert panel.legend and lay.legend.top() >= lay.axes.bottom()
    assert lay.legend.height() >= small_fm.lineSpacing() * len(panel.legend)
    # The colour bar's label is no longer than its bar (it runs along it).
    bar = window.map_view.picture.bar
    assert max(small_fm.horizontalAdvance(t) for t in bar.label.split("\n")) <= canvas.bar_rect.height() + 1


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


def test_closed_error_dialogs_do_not_pile_up(make_window, qtbot):
    """Each error after the last dialog was closed opens a new one; the closed ones are deleted
    (a soak with a failing preset gained 5 widgets and a top-level window per error)."""
    window = make_window("fivebar_singh", longest=40)
    for k in range(6):
        window.show_error(f"failure {k}")
        window.error_box.close()
        qtbot.wait(10)
    assert len(window.findChildren(QMessageBox)) == 1


@pytest.mark.parametrize("quantity", ["isotropic_force", "condition_number"])
def test_the_map_on_screen_and_the_exported_figure_show_the_same_data_and_colours(make_window, qtbot, quantity):
    window = make_window("fivebar_singh", longest=60)
    window.quantity_box.setCurrentIndex(window.quantity_box.findData(quantity))
    qtbot.waitUntil(lambda: window.state.current is not None and quantity in window.state.current.map.values
                    and window.state.current.stage == "full" and not window.state.busy, timeout=30_000)
    st = window.state
    panel = window.map_view.picture.panels[0]
    exported = map_figure(st.current.map, quantity, st.preset).axes[0].images[0]
    a, b = panel.data, exported.get_array().T          # the exported image is (ny, nx)
    mask = np.ma.getmaskarray(a)
    np.testing.assert_array_equal(mask, np.ma.getmaskarray(b))
    np.testing.assert_array_equal(np.ma.getdata(a)[~mask], np.ma.getdata(b)[~mask])
    assert panel.scale.limits == exported.get_clim()
    assert type(matplotlib_norm(panel.scale)) is type(exported.norm)
    # The same colour at every sample: the screen's lookup against matplotlib's norm and colour map.
    screen_rgba = colour_samples(panel.scale, a)
    export_rgba = exported.to_rgba(exported.get_array(), bytes=True).transpose(1, 0, 2)
    np.testing.assert_array_equal(screen_rgba[~mask], export_rgba[~mask])
    # And those colours are the pixels painted: the sample under each probed pixel's centre.
    rgb = widget_rgb(window.map_view.canvas).astype(float)
    (lay,) = window.map_view.canvas.layouts
    ex0, ex1, ey0, ey1 = panel.extent
    nx, ny = a.shape
    rng = np.random.default_rng(1)
    hits = total = 0
    for _ in range(400):
        px = int(rng.uniform(lay.axes.left() + 2, lay.axes.right() - 2))
        py = int(rng.uniform(lay.axes.top() + 2, lay.axes.bottom() - 2))
        _, x, y = window.map_view.canvas.to_data(px + 0.5, py + 0.5)
        i, j = int((x - ex0) / (ex1 - ex0) * nx), int((y - ey0) / (ey1 - ey0) * ny)
        if not (0 <= i < nx and 0 <= j < ny) or mask[i, j]:
            continue
        total += 1
        hits += np.array_equal(rgb[py, px], screen_rgba[i, j, :3].astype(float))
    # Markers (extremes, pose, singular points) cover a few of the probed pixels.
    assert total > 50 and hits >= 0.9 * total, (hits, total)


def test_the_status_bars_pose_label_keeps_its_size_through_similar_texts(make_window):
    """The pose label is fixed-size, so a new text each slider step does not lay the window out
    again; it grows to a longer text and shrinks back once the text needs well under its width."""
    window = make_window()
    label = window.pose_label
    window._show_pose_text("pose unreachable")      # from a short text (the device's own pose may be longer)
    window._show_pose_text("isotropic 4.01 N (theta_0 limits), cond 1.4; continuous rating, gravity off")
    size = label.maximumSize()
    assert label.minimumSize() == size                               # fixed: no layout request per text
    window._show_pose_text("isotropic 3.98 N (theta_0 limits), cond 1.3; continuous rating, gravity off")
    assert label.maximumSize() == size
    longer = "isotropic 4.02 N (theta_0 limits), cond 1.41  [outside limits]; peak rating, gravity upright"
    window._show_pose_text(longer)
    assert label.maximumWidth() == QLabel(longer).sizeHint().width() > size.width()
    window._show_pose_text("pose unreachable")
    assert label.maximumWidth() == QLabel("pose unreachable").sizeHint().width() < size.width()


def test_the_objects_alive_at_start_up_are_left_out_of_full_garbage_collections(make_window):
    """A full pass of the collector over the libraries' and the window's objects held the GIL
    for ~100 ms (``scripts/bench_gui.py``'s refine blocks): the window freezes them at start-up,
    so a later pass sees only what came after."""
    import gc

    window = make_window()
    assert gc.get_freeze_count() > 10_000
    assert not any(o is window for o in gc.get_objects())        # the window itself is frozen
