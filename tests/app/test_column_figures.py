"""``isoforce figure --width-in W --font-pt P``: a flat view laid out for a journal column.

The page is exactly W inches wide (PDF MediaBox, SVG width), every text is inside it, the
body text is P points, and bad combinations exit 2 naming the flag, leaving no file.
"""
from __future__ import annotations

import re

import pytest

from app.cli import main
from app.plots.figures import BODY_PT, fit_to_column, map_figure
from metrics.workspace import compute_map
from resources import load_preset


def small_map(key="inverse3_prototype", n=60):
    preset = load_preset(key)
    return preset, compute_map(preset.mechanism, preset.grid.with_resolution((n, n)), ("isotropic_force",))


def test_a_map_pdf_is_the_column_wide(tmp_path, capsys):
    out = tmp_path / "m.pdf"
    assert main(["figure", "inverse3_prototype", "--view", "map", "--width-in", "3.5", "--font-pt", "8",
                 "--resolution", "60", "--out", str(out)]) == 0
    box = re.search(rb"/MediaBox \[ 0 0 ([\d.]+) ([\d.]+) \]", out.read_bytes())
    assert float(box.group(1)) == pytest.approx(3.5 * 72)          # 252 pt
    svg = tmp_path / "m.svg"
    assert main(["figure", "inverse3_prototype", "--view", "map", "--width-in", "3.5", "--resolution", "60",
                 "--out", str(svg)]) == 0
    assert re.search(r'width="252(\.0+)?pt"', svg.read_text())


def test_every_text_is_inside_the_page_at_the_asked_size():
    preset, wmap = small_map()
    fig = fit_to_column(map_figure(wmap, "isotropic_force", preset), 3.5, 8.0)
    renderer = fig.canvas.get_renderer()
    fig.draw_without_rendering()
    width, height = fig.get_size_inches()
    drawn = fig.get_tightbbox(renderer)               # inches: everything drawn, as matplotlib sees it
    assert -0.01 <= drawn.x0 and drawn.x1 <= width + 0.01 and -0.01 <= drawn.y0 and drawn.y1 <= height + 0.01
    ax = fig.axes[0]
    page = fig.bbox
    named = [ax.title, ax.xaxis.label, ax.yaxis.label, *fig.legends[0].get_texts(), fig.axes[1].yaxis.label]
    for text in named:
        box = text.get_window_extent(renderer)
        assert page.x0 - 0.5 <= box.x0 and box.x1 <= page.x1 + 0.5, text.get_text()
        assert page.y0 - 0.5 <= box.y0 and box.y1 <= page.y1 + 0.5, text.get_text()
    title = fig.axes[0].title
    assert title.get_fontsize() == pytest.approx(8.0 * 10.0 / BODY_PT)
    assert fig.get_size_inches()[0] == pytest.approx(3.5)


def test_a_font_too_large_for_the_column_is_refused_with_the_sizes():
    preset, wmap = small_map()
    with pytest.raises(ValueError, match="1.2 in"):
        fit_to_column(map_figure(wmap, "isotropic_force", preset), 1.2, 20.0)


@pytest.mark.parametrize("extra, phrase", [
    (["--font-pt", "8"], "--font-pt needs --width-in"),
    (["--width-in", "0.5"], "--width-in must be 1 to 20 in"),
    (["--width-in", "3.5", "--font-pt", "50"], "--font-pt must be 4 to 30 pt"),
    (["--width-in", "3.5", "--size", "800x600"], "give one"),
])
def test_bad_column_options_exit_2_naming_the_flag(tmp_path, capsys, extra, phrase):
    out = tmp_path / "x.pdf"
    argv = ["figure", "inverse3_prototype", "--resolution", "40", "--out", str(out)] + extra
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert phrase in err and "Traceback" not in err
    assert not out.exists()


def test_a_wide_map_keeps_a_readable_page_and_wraps_its_title():
    """The five-bar's map is twice as wide as tall: its page is no flatter than MIN_COLUMN_ASPECT."""
    from app.plots.figures import MIN_COLUMN_ASPECT

    preset, wmap = small_map("fivebar_singh")
    fig = fit_to_column(map_figure(wmap, "isotropic_force", preset), 3.5, 8.0)
    width, height = fig.get_size_inches()
    assert width == pytest.approx(3.5) and height >= MIN_COLUMN_ASPECT * 3.5 - 1e-9
    assert all(len(line) <= 60 for line in fig.axes[0].get_title().split("\n"))
