"""``isoforce figure`` with several devices and views in one run, and 3D views laid out for a column.

Several DEVICEs and views share one start-up: each figure is named by ``--out`` with ``{device}``
and ``{view}`` (or ``--out-dir`` with ``--format``), names that cannot tell two figures apart are
refused before anything is computed, and the files are written all or none. The 3D views take
``--width-in``/``--font-pt``: a page that many inches wide (PDF MediaBox, SVG width), vector text
at that size, the picture one raster image at ``PRINT_DPI`` (VTK exports 3D props as pixels only,
which the written line says), and a compact caption.
"""
from __future__ import annotations

import re
import shutil
import zlib
from pathlib import Path

import matplotlib
import matplotlib.image
import numpy as np
import pytest

from app.cli import main
from app.render.views import compact_caption
from app.scenes.snapshot import PRINT_DPI, RASTER_NOTE

ROOT = Path(__file__).resolve().parents[2]
FAST = ("--resolution", "21")


def figure(capsys, *argv: str) -> tuple[int, str, str]:
    capsys.readouterr()
    status = main(["figure", *argv])
    out, err = capsys.readouterr()
    return status, out, err


def pdf_streams(data: bytes) -> bytes:
    """Every stream of a PDF, inflated where it is Flate-compressed (matplotlib's are)."""
    chunks = []
    for match in re.finditer(rb"stream\r?\n(.*?)\r?\nendstream", data, re.S):
        raw = match.group(1)
        try:
            chunks.append(zlib.decompress(raw))
        except zlib.error:
            chunks.append(raw)
    return b"\n".join(chunks)


def media_box(data: bytes) -> tuple[float, float]:
    box = re.search(rb"/MediaBox \[ *0 0 ([\d.]+) ([\d.]+) *\]", data)
    return float(box.group(1)), float(box.group(2))


# -- several devices -------------------------------------------------------------------------
def test_several_devices_and_views_in_one_run_are_each_single_runs_figure(capsys, tmp_path):
    """``DEVICE DEVICE --view map,pose``: one file per device and view, named by {device}_{view},
    pixel for pixel what a run of that device and view alone writes."""
    devices, views = ("fivebar_singh", "haply_2diy"), ("map", "pose")
    status, out, err = figure(capsys, *devices, *FAST, "--size", "400x300", "--view", ",".join(views),
                              "--out", str(tmp_path / "all_{device}_{view}.png"))
    assert status == 0 and err == "", err
    names = [f"all_{d}_{v}.png" for d in devices for v in views]
    assert out.splitlines() == [f"wrote {tmp_path / n}" for n in names]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
    for device in devices:
        for view in views:
            status, _, err = figure(capsys, device, *FAST, "--size", "400x300", "--view", view,
                                    "--out", str(tmp_path / f"one_{device}_{view}.png"))
            assert status == 0, err
            batch, alone = (matplotlib.image.imread(tmp_path / f"{w}_{device}_{view}.png") for w in ("all", "one"))
            np.testing.assert_array_equal(batch, alone, err_msg=f"{device} {view}")


def test_out_dir_names_each_figure_device_underscore_view_in_the_format(capsys, tmp_path):
    status, out, err = figure(capsys, "fivebar_singh", "haply_2diy", *FAST, "--view", "map,bands",
                              "--out-dir", str(tmp_path), "--format", "svg")
    assert status == 0, err
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(f"{d}_{v}.svg" for d in ("fivebar_singh", "haply_2diy") for v in ("map", "bands"))
    assert all((tmp_path / n).read_text().lstrip().startswith("<?xml") for n in names)


def test_a_toml_device_is_named_by_its_file_name(capsys, tmp_path):
    toml = tmp_path / "my_pen.toml"
    shutil.copy(ROOT / "resources" / "presets" / "fivebar_singh.toml", toml)
    status, out, err = figure(capsys, str(toml), "fivebar_singh", *FAST, "--out", str(tmp_path / "{device}.png"))
    assert status == 0, err
    assert {p.name for p in tmp_path.iterdir()} == {"my_pen.toml", "my_pen.png", "fivebar_singh.png"}


@pytest.mark.parametrize("argv, phrase", [
    (["fivebar_singh", "haply_2diy", "--out", "{tmp}/m.png"], "--out needs {device} in its name for several devices"),
    (["fivebar_singh", "haply_2diy", "--view", "map,pose", "--out", "{tmp}/{device}.png"], "--out needs {view}"),
    (["fivebar_singh", "--out", "{tmp}/{devce}.png"], "--out: unknown field {devce}"),
    (["fivebar_singh", "--out", "{tmp}/m.png", "--out-dir", "{tmp}"], "--out and --out-dir both name the files"),
    (["fivebar_singh"], "--out FILE or --out-dir DIR is required"),
    (["fivebar_singh", "--out", "{tmp}/m.png", "--format", "pdf"], "--format applies to --out-dir"),
    (["fivebar_singh", "--out-dir", "{tmp}/missing"], "--out-dir: folder"),
    (["fivebar_singh", "haply_2diy", "--set", "proximal=80", "--out", "{tmp}/{device}.png"],
     "--set changes one device's design"),
    # A device-specific refusal names the device, and comes before any map of the others is computed.
    (["fivebar_singh", "inverse3_prototype", "--view", "ellipses", "--out", "{tmp}/{device}.png"],
     "DEVICE 'inverse3_prototype': --view ellipses needs a planar device"),
])
def test_outputs_that_cannot_tell_figures_apart_are_refused_before_computing(capsys, tmp_path, monkeypatch, argv,
                                                                              phrase):
    import app.cli.figure as figure_cli

    def no_map(*args, **kwargs):
        raise AssertionError("a map was computed before the arguments were checked")

    monkeypatch.setattr(figure_cli, "compute_map", no_map)
    status, out, err = figure(capsys, *[a.replace("{tmp}", str(tmp_path)) for a in argv])
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and phrase in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_two_devices_on_one_file_are_refused(capsys, tmp_path):
    """Two DEVICE files of one name in different folders would write one figure over the other."""
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        shutil.copy(ROOT / "resources" / "presets" / "fivebar_singh.toml", tmp_path / folder / "pen.toml")
    status, out, err = figure(capsys, str(tmp_path / "a" / "pen.toml"), str(tmp_path / "b" / "pen.toml"),
                              "--out", str(tmp_path / "{device}.png"))
    assert status == 2 and "would both write" in err and "pen.png" in err
    assert not (tmp_path / "pen.png").exists()


@pytest.mark.parametrize("failure", [ValueError("the map could not be drawn"), KeyboardInterrupt()])
def test_a_failure_or_an_interrupt_at_the_last_figure_leaves_no_file(capsys, tmp_path, monkeypatch, failure):
    """All or none over devices too: the second device's failing view (or Ctrl-C there) leaves none of
    the run's files, no temporary, and an older file of a target's name as it was."""
    import app.cli.figure as figure_cli
    real = figure_cli.export_view
    drawn = []

    def export_view(view, path, **kwargs):
        if kwargs["preset"].key == "haply_2diy" and view == "map":
            raise failure
        drawn.append(view)
        return real(view, path, **kwargs)

    monkeypatch.setattr(figure_cli, "export_view", export_view)
    old = tmp_path / "fivebar_singh_pose.png"
    old.write_bytes(b"old")
    status, out, err = figure(capsys, "fivebar_singh", "haply_2diy", *FAST, "--size", "300x200",
                              "--view", "pose,map", "--out", str(tmp_path / "{device}_{view}.png"))
    assert drawn == ["pose", "map", "pose"]
    assert status == (130 if isinstance(failure, KeyboardInterrupt) else 2) and out == ""
    if not isinstance(failure, KeyboardInterrupt):
        assert "DEVICE 'haply_2diy' --view map: the map could not be drawn; no file written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fivebar_singh_pose.png"] and old.read_bytes() == b"old"


# -- 3D views for a column -------------------------------------------------------------------
@pytest.mark.parametrize("view", ["pose", "workspace"])
def test_a_3d_pdf_for_a_column_is_that_wide_with_vector_text_and_one_print_raster(capsys, tmp_path, view):
    out = tmp_path / f"{view}.pdf"
    status, written, err = figure(capsys, "fivebar_singh", *FAST, "--view", view, "--width-in", "3.5",
                                  "--font-pt", "8", "--out", str(out))
    assert status == 0 and err == "", err
    assert written.strip() == f"wrote {out} ({RASTER_NOTE})"
    data = out.read_bytes()
    width, height = media_box(data)
    assert width == pytest.approx(3.5 * 72) and 0.5 * width < height < 3 * width
    content = pdf_streams(data)
    # Vector graphics besides the picture: text objects, and paths (the scale bar, the triad's arrows).
    assert content.count(b"BT") >= 3 and b" Tf" in content
    assert re.search(rb"\d m\n", content) and re.search(rb"\d l\n", content)
    # The picture: one image XObject (besides a colour bar's strip of colours), PRINT_DPI at its
    # size on the page.
    images = [(int(w), int(h)) for w, h in re.findall(rb"/Subtype /Image /Width (\d+) /Height (\d+)", data)]
    pictures = [(w, h) for w, h in images if h > 20]
    assert len(pictures) == 1 and len(images) <= 2
    placed = max(float(w) for w in re.findall(rb"([\d.]+) 0 0 -?[\d.]+ -?[\d.]+ -?[\d.]+ cm\s*/I\d+ Do", content))
    assert pictures[0][0] / (placed / 72) == pytest.approx(PRINT_DPI, rel=0.02)


def test_a_3d_svg_for_a_column_has_its_text_at_the_size_and_the_compact_caption(capsys, tmp_path):
    out = tmp_path / "pose.svg"
    status, _, err = figure(capsys, "fivebar_singh", *FAST, "--view", "pose", "--width-in", "3.5", "--font-pt", "7",
                            "--out", str(out))
    assert status == 0, err
    svg = out.read_text()
    assert re.search(r'<svg[^>]* width="252(\.0+)?pt"', svg)
    sizes = {float(s) for s in re.findall(r"font-size: ([\d.]+)px", svg)}
    assert 7.0 in sizes and min(sizes) >= 7.0 - 1e-6           # the body text, nothing smaller
    text = " ".join(re.findall(r"<text[^>]*>([^<]*)</text>", svg))
    assert "at (0.0, 150.0) mm" in text and "(x, y) =" not in text      # the compact caption
    assert svg.count("<image") == 1


def test_a_3d_png_for_a_column_is_that_wide_at_the_print_resolution(capsys, tmp_path):
    out = tmp_path / "w.png"
    status, written, err = figure(capsys, "fivebar_singh", *FAST, "--view", "workspace", "--width-in", "3.5",
                                  "--out", str(out))
    assert status == 0, err
    assert RASTER_NOTE not in written                                  # a PNG is pixels anyway
    assert matplotlib.image.imread(out).shape[1] == pytest.approx(3.5 * PRINT_DPI, abs=1)


def test_the_compact_caption_keeps_every_number_on_fewer_lines():
    full = ("at (x, y, z) = (170.0, 22.3, 230.0) mm; continuous rating, gravity off\n"
            "isotropic force 4.01 N (theta_0 limits), anisotropic 8.02 N, condition 1.4\n"
            "forces drawn at 10 N = 68 mm; linear velocity ellipsoid at 1 m/s = 250 mm")
    short = compact_caption(full)
    assert "\n" not in short and len(short) < len(full)
    assert re.findall(r"\d+(?:\.\d+)?", short) == re.findall(r"\d+(?:\.\d+)?", full)


@pytest.mark.parametrize("device, view", [("inverse3_prototype", "pose"), ("twin_pantograph", "pose"),
                                          ("inverse3_prototype", "workspace"), ("novint_falcon", "workspace")])
def test_a_column_3d_figure_has_every_text_inside_apart_and_at_the_size(capsys, tmp_path, monkeypatch, device, view):
    """Title, legend, scale bar, triad, colour bar and the compact caption: each inside the 3.5 in
    page, none over another, the caption at --font-pt."""
    import matplotlib.text

    from app.scenes import snapshot
    figures = []
    real = snapshot.SceneFigure.save

    def save(self, path):
        figures.append(self.figure)
        return real(self, path)

    monkeypatch.setattr(snapshot.SceneFigure, "save", save)
    status, _, err = figure(capsys, device, "--resolution", "15", "--view", view, "--width-in", "3.5",
                            "--font-pt", "8", "--out", str(tmp_path / "f.pdf"))
    assert status == 0, err
    fig, = figures
    fig.canvas.draw()                          # the layout as drawn on its own canvas
    renderer = fig.canvas.get_renderer()
    # (a class legend takes the place of a colour bar whose axes, with its texts, is hidden)
    hidden = {t for ax in fig.axes if not ax.get_visible() for t in ax.findobj(matplotlib.text.Text)}
    texts = [t for t in fig.findobj(matplotlib.text.Text)
             if t.get_text().strip() and t.get_visible() and t not in hidden]
    boxes = [t.get_window_extent(renderer) for t in texts]
    page = fig.bbox
    for text, box in zip(texts, boxes):
        assert page.x0 - 0.5 <= box.x0 <= box.x1 <= page.x1 + 0.5, text.get_text()
        assert page.y0 - 0.5 <= box.y0 <= box.y1 <= page.y1 + 0.5, text.get_text()
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            assert not boxes[i].overlaps(boxes[j]), (texts[i].get_text(), texts[j].get_text())
    assert fig.get_size_inches()[0] == pytest.approx(3.5)
    caption = [t for t in texts if " mm" in t.get_text() and t.get_fontsize() < 9]
    assert caption and all(t.get_fontsize() == pytest.approx(8.0) for t in caption)


def test_vtks_vector_export_still_writes_3d_geometry_as_pixels(tmp_path):
    """Why the 3D views embed a raster (``app.scenes.snapshot``): VTK's GL2PS exporter, asked for
    vectors (``Write3DPropsAsRasterImage`` off), writes a lit sphere as one image and no polygon,
    off-screen here as on a display. When a VTK writes polygons this fails: use its vectors then."""
    from app.scenes.snapshot import use_headless_gl
    use_headless_gl()
    import pyvista as pv
    import vtkmodules.vtkRenderingGL2PSOpenGL2  # noqa: F401  (GL2PS's OpenGL2 helpers)
    from vtkmodules.vtkIOExportGL2PS import vtkGL2PSExporter

    plotter = pv.Plotter(off_screen=True, window_size=(200, 150))
    try:
        plotter.add_mesh(pv.Sphere(), color="red")
        plotter.render()
        exporter = vtkGL2PSExporter()
        exporter.SetRenderWindow(plotter.render_window)
        exporter.SetFilePrefix(str(tmp_path / "sphere"))
        exporter.SetFileFormatToSVG()
        exporter.CompressOff()
        exporter.SetWrite3DPropsAsRasterImage(False)
        exporter.Write()
    finally:
        plotter.close()
    svg = (tmp_path / "sphere.svg").read_text()
    assert svg.count("<image") == 1
    assert not re.search(r"<(polygon|path|polyline)\b", svg)
