"""3D views as figures (``app.scenes.snapshot``): cropped to content, a true scale bar, legible text, small files.

The scale is checked against the rendered pixels of a mesh of known size (not against the
formula that drew the bar), the crop against the image's non-white box, the fonts against
the image height in the SVG the command writes.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import matplotlib
import matplotlib.image
import numpy as np
import pytest

from app.cli import main
from app.render.views import _plotter
from app.scenes import snapshot


def content_box(pixels: np.ndarray) -> tuple[int, int, int, int]:
    """Rows and columns (first, last) of the non-white pixels."""
    ink = np.any(pixels[..., :3] < 0.97 if pixels.dtype != np.uint8 else pixels[..., :3] < 247, axis=-1)
    rows, cols = np.nonzero(ink.any(axis=1))[0], np.nonzero(ink.any(axis=0))[0]
    return rows[0], rows[-1], cols[0], cols[-1]


@pytest.mark.parametrize("box_mm, view", [((100.0, 50.0, 0.0), "xy"), ((30.0, 40.0, 80.0), "iso")])
def test_fit_camera_scale_is_what_the_pixels_show(box_mm, view):
    import pyvista as pv
    plotter = _plotter((400, 300))
    try:
        w, h, d = (v / 1e3 for v in box_mm)
        mesh = pv.Box(bounds=(0.01, 0.01 + w, -0.02, -0.02 + h, 0.0, d)) if d else pv.Plane(
            center=(0.01 + w / 2, -0.02 + h / 2, 0.0), i_size=w, j_size=h)
        plotter.add_mesh(mesh, color="black", lighting=False)
        plotter.view_xy() if view == "xy" else plotter.view_isometric()
        (pw, ph), px_per_m = snapshot.fit_camera(plotter, (400, 300))
        image = plotter.screenshot(None, return_img=True)
    finally:
        plotter.close()
    assert image.shape[:2] == (ph, pw)
    r0, r1, c0, c1 = content_box(image)
    if view == "xy":
        # The rectangle's pixels: (w px_per_m) x (h px_per_m), +-1 px of rasterisation at each edge.
        assert c1 - c0 + 1 == pytest.approx(w * px_per_m, abs=2)
        assert r1 - r0 + 1 == pytest.approx(h * px_per_m, abs=2)
    else:
        # Isometric: the box's outline spans its projected extent, sqrt(2/3)(...) for the vertical one.
        corners = np.array([[x, y, z] for x in (0, w) for y in (0, h) for z in (0, d)])
        up = np.array([-1.0, -1.0, 2.0]) / np.sqrt(6.0)
        assert r1 - r0 + 1 == pytest.approx(np.ptp(corners @ up) * px_per_m, abs=2)
    # Cropped: the content fills the window to its margin on the limiting side, on both sides.
    margin = snapshot.MARGIN_SHARE * 300
    assert min(c0, r0, pw - 1 - c1, ph - 1 - r1) <= margin + 1
    assert max(c0 + (pw - 1 - c1), r0 + (ph - 1 - r1)) <= 2 * margin + 3     # no empty band beyond the margins


def test_pose_figure_is_cropped_to_its_content(capsys, tmp_path):
    out = tmp_path / "pose.png"
    assert main(["figure", "inverse3_prototype", "--view", "pose", "--size", "800x600", "--out", str(out)]) == 0
    image = matplotlib.image.imread(out)
    r0, r1, c0, c1 = content_box(image)
    # Before: 60 % of the canvas around the device was empty. Now the ink spans the figure up to
    # the margins (the device, or the caption under it, whichever is wider).
    assert (c1 - c0 + 1) / image.shape[1] > 0.9 and (r1 - r0 + 1) / image.shape[0] > 0.9
    assert image.shape[0] <= 600 and image.shape[1] <= 800


@pytest.fixture
def svg_text_as_text(monkeypatch):
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")


@pytest.mark.parametrize("view, size", [("pose", "1600x1200"), ("workspace", "800x600"), ("pose", "400x300")])
def test_text_is_legible_at_the_exported_size_and_the_file_is_small(capsys, tmp_path, svg_text_as_text, view, size):
    out = tmp_path / "view.svg"
    argv = ["figure", "inverse3_prototype", "--view", view, "--size", size, "--resolution", "61", "--out", str(out)]
    assert main(argv) == 0
    root = ET.parse(out).getroot()
    height_pt = float(root.get("height").removesuffix("pt"))
    sizes = [float(m) for m in re.findall(r"font-size:\s*([\d.]+)px", out.read_text())]    # user units: pt
    assert sizes, "no text in the SVG"
    # The smallest text is at least 1.5 % of the image height (or the 9 px floor, for small images).
    requested = int(size.split("x")[1])
    floor = max(0.015 * requested, snapshot.MIN_FONT_PX) * 72.0 / snapshot.DPI          # pt
    assert min(sizes) >= floor * (1 - 1e-6) and height_pt <= requested * 72.0 / snapshot.DPI + 1
    # One raster picture, not the scene's triangles (VTK's GL2PS export wrote 5.7 MB for a pose).
    assert out.stat().st_size < 400_000
    images = [el for el in root.iter() if el.tag.endswith("image")]
    assert len(images) == (2 if view == "workspace" else 1)          # the picture (and the colour bar)
    assert len([el for el in root.iter() if el.tag.endswith("path")]) < 100     # no triangles


def test_pose_pdf_is_small(capsys, tmp_path):
    out = tmp_path / "pose.pdf"
    assert main(["figure", "inverse3_prototype", "--view", "pose", "--out", str(out)]) == 0
    data = out.read_bytes()
    assert data.startswith(b"%PDF-") and len(data) < 400_000


def test_an_unreachable_pose_has_its_caption_and_no_scale(tmp_path, svg_text_as_text):
    from app.render.views import export_view
    from resources import load_preset
    preset = load_preset("fivebar_singh")
    out = export_view("pose", tmp_path / "pose.svg", preset=preset, mechanism=preset.mechanism, workspace_map=None,
                      quantity="isotropic_force", pose=(0.0, 0.5), size=(400, 300))      # 500 mm: out of reach
    text = " ".join(" ".join(el.itertext()) for el in ET.parse(out).iter() if el.tag.endswith("text"))
    assert "pose unreachable" in text
    from app.render.views import pose_text
    where = pose_text(preset.mechanism, (0.0, 0.5))
    assert where in text                                       # where it was asked for, in mm
    assert " mm" not in text.replace(preset.name, "").replace(where, "")   # no scale bar for an empty scene


def test_an_exported_pose_is_analysed_under_the_apps_loading(tmp_path, svg_text_as_text):
    """The app exports its pose under its own rating and gravity (``loading``): the figure's
    caption says that loading, and its isotropic force is the pose analysis under it, not the
    unloaded one (the export had always analysed the pose at continuous rating, gravity off)."""
    from app.render.views import export_view
    from metrics.loading import Loading
    from metrics.pose import analyse_pose
    from resources import load_preset
    preset = load_preset("phantom_premium_15")
    loading = Loading(rating="peak", gravity=(0.0, 0.0, -9.80665))
    out = export_view("pose", tmp_path / "pose.svg", preset=preset, mechanism=preset.mechanism, workspace_map=None,
                      quantity="isotropic_force", pose=preset.pose, size=(800, 600), loading=loading)
    text = " ".join(" ".join(" ".join(el.itertext()) for el in ET.parse(out).iter() if el.tag.endswith("text")).split())
    loaded = analyse_pose(preset.mechanism, np.asarray(preset.pose), loading=loading)
    unloaded = analyse_pose(preset.mechanism, np.asarray(preset.pose))
    assert f"{loaded.isotropic_force:.3g}" != f"{unloaded.isotropic_force:.3g}"
    assert loading.describe() in text and f"isotropic force {loaded.isotropic_force:.3g} N" in text


def greedy_wrap(text: str, font_px: float, width_px: float) -> list[str]:
    """The reference: ``snapshot._text_block``'s rule applied word by word, with no shortcut (each
    word too wide alone split at its glued spaces, then words added while the line fits)."""
    lines = []
    for line in snapshot.CAPTION_GLUE.sub("\u00a0", text).splitlines():
        words = []
        for word in line.split(" "):
            words += word.split("\u00a0") if snapshot._text_width(word, font_px) > width_px else [word]
        current = ""
        for word in words:
            trial = f"{current} {word}" if current else word
            if current and snapshot._text_width(trial, font_px) > width_px:
                lines.append(current)
                current = word
            else:
                current = trial
        lines.append(current)
    return [line.replace("\u00a0", " ") for line in lines]


def test_a_caption_wraps_as_the_greedy_wrap_word_by_word():
    """``_text_block`` keeps a line that fits whole after measuring it once and finds each break of
    one that does not by bisection; word by word (the reference) gives the same lines at every
    width, including a line's own width, a pixel less (where the wrap must break) and widths
    narrower than some glued phrase."""
    from app import scenes
    from app.render.views import pose_text
    from metrics.pose import analyse_pose
    from resources import load_preset

    captions = []
    for key in ("inverse3_prototype", "fivebar_singh", "twin_pantograph"):
        preset = load_preset(key)
        report = analyse_pose(preset.mechanism, np.asarray(preset.pose, float))
        captions.append(pose_text(preset.mechanism, preset.pose) + "; " + report.loading.describe() + "\n"
                        + scenes.pose_caption(report, 0.01, None, ""))
    captions.append("at zero force: isotropic moment 0.347 N m, anisotropic 0.869 N m\n\nx = 12.5 mm")
    captions.append("  two  spaces   here and  there, 1 m/s = 250 mm  ")      # empty words kept as the wrap keeps them
    checked = broken = 0
    for text in captions:
        for font_px in (9.0, 26.4):
            exact = [snapshot._text_width(line, font_px) for line in snapshot.CAPTION_GLUE.sub(" ", text).splitlines()]
            widths = {w + d for w in exact for d in (0.0, -1.0, -0.25 * w, -0.6 * w)} | {40.0, 200.0, 5000.0}
            for width in sorted(w for w in widths if w > 0):
                got = snapshot._text_block(text, font_px, width)
                assert got == greedy_wrap(text, font_px, width), (text, font_px, width)
                checked += 1
                broken += len(got) > len(text.splitlines())
    assert checked > 50 and broken > 10          # the widths made it wrap, and keep whole, many times
