"""``isoforce figure``: the app's views rendered off-screen to PNG/SVG/PDF, with no display.

One subprocess renders every view in every format with ``DISPLAY`` unset (the claim that
no display is needed, and that no Qt is loaded); the in-process tests check what the
figures say against the compute layer (text in SVGs, pixels of a glyph's colour) and that
bad input gets one line naming the argument, exit status 2 and no file.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib
import matplotlib.image
import numpy as np
import pytest
from matplotlib.colors import to_rgb

from app import scenes
from app.cli import main
from app.logic.figure_digits import format_with_error, shown_error
from app.logic.glyphs import seen_colour
from app.scenes.pose import FLAT_OPACITY
from metrics.pose import analyse_pose
from metrics.quantities import CORE_QUANTITIES, QUANTITIES
from metrics.workspace import compute_map
from resources import load_preset

ROOT = Path(__file__).resolve().parents[2]
VIEWS = ("map", "pose", "workspace", "compare", "bands", "ellipses")
FORMATS = (".png", ".svg", ".pdf")
NEEDED = tuple(sorted(set(CORE_QUANTITIES) | {"isotropic_force"}))   # what the command computes


def figure(capsys, *argv: str) -> tuple[int, str]:
    capsys.readouterr()
    status = main(["figure", *argv])
    out, err = capsys.readouterr()
    assert status != 0 or err == ""          # a figure written says so on stdout; stderr is for errors
    return status, out + err


def svg_text(path: Path) -> str:
    """All text of an SVG (matplotlib's, written as text with ``svg.fonttype = none``)."""
    return " ".join(" ".join(el.itertext()) for el in ET.parse(path).iter() if el.tag.endswith("text"))


@pytest.fixture
def svg_text_as_text(monkeypatch):
    """matplotlib writes SVG text as text, not glyph paths, so the tests can read it."""
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")


# -- headless --------------------------------------------------------------------------------
HEADLESS = r"""
import json, sys
from app.cli import main
out, jobs = sys.argv[1], json.loads(sys.argv[2])
status, qt = {}, {}
for name, argv in jobs.items():
    status[name] = main(["figure", *argv, "--out", f"{out}/{name}"])
    qt[name] = sorted({m.split(".")[0] for m in sys.modules} & {"PySide6", "shiboken6", "PyQt5", "PyQt6", "pyvistaqt"})
print(json.dumps({"status": status, "qt": qt}))
"""
NO_DISPLAY = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}


def run_headless(out: Path, jobs: dict) -> dict:
    """Run ``isoforce figure`` for each job in one fresh interpreter with no display."""
    result = subprocess.run([sys.executable, "-c", HEADLESS, str(out), json.dumps(jobs)], cwd=ROOT, env=NO_DISPLAY,
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["status"] == {name: 0 for name in jobs}, result.stderr
    return report, result.stderr


def test_every_view_renders_to_every_format_with_no_display(tmp_path):
    jobs = {}
    for view in VIEWS:
        for suffix in FORMATS:
            device = "inverse3_prototype" if view in ("workspace", "compare") else "fivebar_singh"
            argv = [device, "--view", view, "--resolution", "41", "--size", "400x300"]
            if view == "compare":
                argv += ["--set", "gear_ratios=13.75,5.957,5.957"]
            jobs[f"{view}{suffix}"] = argv
    report, stderr = run_headless(tmp_path, jobs)
    assert report["qt"] == {name: [] for name in jobs}           # no view loads Qt
    # Silent on stderr: no VTK "bad X server connection" (or any other) warning; "wrote" goes to stdout
    assert stderr == "", stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(jobs)      # and no temporary files
    for name in jobs:
        path = tmp_path / name
        if path.suffix == ".png":
            image = matplotlib.image.imread(path)
            if name.startswith(("pose", "workspace")):       # 3D views are cropped to their content
                assert 150 <= image.shape[0] <= 300 and 200 <= image.shape[1] <= 400, (name, image.shape)
            else:
                assert image.shape[:2] == (300, 400), name
            assert np.ptp(image[..., :3]) > 0.1, name        # something was drawn
        elif path.suffix == ".svg":
            assert ET.parse(path).getroot().tag.endswith("svg"), name
        else:
            data = path.read_bytes()
            assert data.startswith(b"%PDF-") and b"%%EOF" in data[-64:], name


# -- what the figures say --------------------------------------------------------------------
def test_map_figure_states_the_compute_layers_grid_and_extremes(capsys, tmp_path, svg_text_as_text):
    preset = load_preset("inverse3_prototype")
    out = tmp_path / "map.svg"
    status, err = figure(capsys, "inverse3_prototype", "--view", "map", "--resolution", "61", "--out", str(out))
    assert status == 0, err
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(61), NEEDED)
    text = svg_text(out)
    assert f"61 x 61 grid, {wmap.feasible_points} feasible points" in text
    stats = wmap.stats["isotropic_force"]
    # With the digits each figure's resolution error supports, as the statistics panel writes them.
    errors = wmap.errors["isotropic_force"]
    for fig in ("min", "max"):
        value = getattr(stats, fig)
        assert f"{fig} {format_with_error(value, shown_error(value, errors[fig]))[0]} N" in text, fig
    assert "Max. isotropic force (N)" in text


def test_compare_figure_states_every_change_of_the_statistics(capsys, tmp_path, svg_text_as_text):
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution(81)
    out = tmp_path / "compare.svg"
    status, err = figure(capsys, "inverse3_prototype", "--view", "compare", "--set", "gear_ratios=13.75,5.957,5.957",
                         "--resolution", "81", "--out", str(out))
    assert status == 0, err
    old = compute_map(preset.mechanism, grid, NEEDED).stats
    new = compute_map(load_preset("inverse3_scenario2").mechanism, grid, NEEDED).stats
    text = " ".join(svg_text(out).split())        # (the lines are wrapped to the figure's width)

    def four(v):        # four significant digits, trailing zeros kept: 2.280, not 2.28
        return f"{v:#.4g}".rstrip(".")
    for q in CORE_QUANTITIES:
        unit = f" ({QUANTITIES[q].unit})" if QUANTITIES[q].unit else ""
        assert f"{QUANTITIES[q].label}{unit}: " in text
        for fig in ("min", "max", "mean", "sd"):
            a, b = getattr(old[q], fig), getattr(new[q], fig)
            assert f"{fig} {four(a)} -> {four(b)} ({100 * (b - a) / abs(a):+.1f} %)" in text, (q, fig)
    assert "reference" in text and "current" in text
    # What was changed, in the --set's own terms.
    assert "Changed (reference -> current): gear_ratios 6.875, 5.957, 5.957 -> 13.75, 5.957, 5.957" in text

    diff = tmp_path / "difference.svg"
    status, err = figure(capsys, "inverse3_prototype", "--view", "compare", "--compare", "difference", "--set",
                         "gear_ratios=13.75,5.957,5.957", "--resolution", "81", "--out", str(diff))
    assert status == 0, err
    assert "current - reference" in svg_text(diff) and "change of max. isotropic force (N)" in svg_text(diff)


@pytest.mark.parametrize("at, bottleneck", [("40,170", "theta_1"), ("-60,120", "theta_2")])
def test_pose_figure_caption_is_the_pose_analysis_there(capsys, tmp_path, svg_text_as_text, at, bottleneck):
    mech = load_preset("fivebar_singh").mechanism
    out = tmp_path / "pose.svg"
    status, err = figure(capsys, "fivebar_singh", "--view", "pose", "--at", at, "--size", "400x300",
                         "--out", str(out))
    assert status == 0, err
    report = analyse_pose(mech, np.array([float(v) for v in at.split(",")]) / 1e3)
    assert report.bottleneck_name == bottleneck
    text = svg_text(out)
    assert (f"isotropic force {report.isotropic_force:.3g} N ({bottleneck} limits), "
            f"anisotropic {report.anisotropic_force:.3g} N, condition {report.condition_number:.3g}") in text
    assert f"10 N = {10 * scenes.force_scale(mech) * 1e3:.0f} mm" in text
    # Where the pose is and under what loading: a printed figure has no toolbar beside it.
    x, y = (float(v) for v in at.split(","))
    assert f"at (x, y) = ({x:.1f}, {y:.1f}) mm; {report.loading.describe()}" in " ".join(text.split())


def test_pose_figure_with_a_desired_force_prints_it_and_its_clamp(capsys, tmp_path, svg_text_as_text):
    """As the app's caption: the clamped arrow lies inside the desired one and the glyphs, so
    the figure says both forces' values (paper 000 eq. 9's clamp, from the pose analysis)."""
    mech = load_preset("fivebar_singh").mechanism
    out = tmp_path / "pose.svg"
    status, err = figure(capsys, "fivebar_singh", "--view", "pose", "--at", "40,170", "--force", "300,-50",
                         "--size", "800x600", "--out", str(out))
    assert status == 0, err
    report = analyse_pose(mech, np.array([40.0, 170.0]) / 1e3)
    desired = np.array([300.0, -50.0])
    clamped = report.clamp(desired)
    assert np.linalg.norm(clamped) < np.linalg.norm(desired) / 5
    text = " ".join(svg_text(out).split())
    assert scenes.force_values_text(desired, clamped, report.force_along(desired)) in text
    # Which clamp it is, and what the actuators hold in that direction (more than the clamp).
    assert "clamped to the isotropic force" in text and "the actuators hold up to" in text
    assert report.force_along(desired) > np.linalg.norm(clamped)


def colour_pixels(path: Path, colour: str) -> int:
    image = matplotlib.image.imread(path)[..., :3]
    return int(np.count_nonzero(np.abs(image - np.array(to_rgb(colour))).max(axis=-1) < 0.03))


def test_glyphs_option_draws_only_the_chosen_glyphs(capsys, tmp_path):
    paths = {}
    for glyphs in ("links", "links,polytope"):
        paths[glyphs] = tmp_path / f"{glyphs.replace(',', '_')}.png"
        status, err = figure(capsys, "fivebar_singh", "--view", "pose", "--at", "40,170", "--glyphs", glyphs,
                             "--size", "400x300", "--out", str(paths[glyphs]))
        assert status == 0, err
    edges, links = scenes.COLOURS["polytope_edges"], scenes.COLOURS["links"]
    assert colour_pixels(paths["links"], edges) == 0
    assert colour_pixels(paths["links,polytope"], edges) > 50
    assert colour_pixels(paths["links"], links) > 20 and colour_pixels(paths["links,polytope"], links) > 20


@pytest.mark.parametrize("key", ["stewart_platform", "twin_pantograph"])
def test_wrench_devices_draw_the_force_set_at_zero_moment(capsys, tmp_path, svg_text_as_text, key):
    """The 3D pose view of a 5- or 6-DOF device draws its zero-moment force polytope and ball (hidden before)."""
    from app.render.views import pose_plotter
    preset = load_preset(key)
    plotter, report = pose_plotter(preset.mechanism, preset.pose, size=(400, 300))
    try:
        for name in ("polytope", "polytope_edges", "sphere"):
            assert name in plotter.actors, name
        # The sphere is the isotropic force at zero moment, at the task point (m), drawn at force_scale.
        scale = scenes.force_scale(preset.mechanism)
        bounds = np.array(plotter.actors["sphere"].GetBounds()).reshape(3, 2)
        np.testing.assert_allclose(bounds.mean(axis=1), np.asarray(preset.pose)[:3], atol=1e-9)
        np.testing.assert_allclose(np.diff(bounds, axis=1)[:, 0] / 2, report.isotropic_force * scale, rtol=0.02)
        points = plotter.actors["polytope"].mapper.dataset.points
        np.testing.assert_allclose(points, np.asarray(preset.pose)[:3] + scale * report.vertices, rtol=1e-12)
    finally:
        plotter.close()
    out = tmp_path / "pose.svg"
    status, err = figure(capsys, key, "--view", "pose", "--size", "400x300", "--out", str(out))
    assert status == 0, err
    text = svg_text(out)
    assert f"at zero moment: isotropic force {report.isotropic_force:.3g} N" in text
    assert f"moments scaled by L = {report.condition_number_scaling['length_m'] * 1e3:.3g} mm" in text


def test_workspace_figure_depends_on_the_quantity(capsys, tmp_path):
    images = {}
    for q in ("isotropic_force", "condition_number"):
        out = tmp_path / f"{q}.png"
        status, err = figure(capsys, "fivebar_singh", "--view", "workspace", "--quantity", q, "--resolution", "41",
                             "--size", "400x300", "--out", str(out))
        assert status == 0, err
        images[q] = matplotlib.image.imread(out)[..., :3]
    assert images["isotropic_force"].shape == images["condition_number"].shape
    assert not np.array_equal(images["isotropic_force"], images["condition_number"])


def test_bands_figure_counts_each_band_of_the_compute_layers_map(capsys, tmp_path, svg_text_as_text):
    from app.plots.overlays import BANDS, condition_bands
    preset = load_preset("fivebar_singh")
    out = tmp_path / "bands.svg"
    status, err = figure(capsys, "fivebar_singh", "--view", "bands", "--resolution", "121", "--out", str(out))
    assert status == 0, err
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(121), NEEDED)
    bands = condition_bands(wmap.values["condition_number"], wmap.feasible)
    text = svg_text(out)
    for k, (name, _) in enumerate(BANDS):
        assert f"{name} ({np.count_nonzero(bands == k)} pts)" in text.replace("&lt;", "<")
    assert "paper 002 dexterous annulus 0.9 L to 1.7 L (L = 93.33 mm)" in text


@pytest.mark.parametrize("kind, unit", [("force", "N"), ("velocity", "m/s per rad/s")])
def test_ellipses_figure_states_its_scale_and_what_it_skipped(capsys, tmp_path, svg_text_as_text, kind, unit):
    from app.plots.overlays import ellipse_field, ellipse_scale
    preset = load_preset("fivebar_singh")
    out = tmp_path / "ellipses.svg"
    status, err = figure(capsys, "fivebar_singh", "--view", "ellipses", "--ellipse", kind, "--spacing", "25",
                         "--resolution", "61", "--out", str(out))
    assert status == 0, err
    field = ellipse_field(preset.mechanism, preset.grid, 0.025, kind=kind)
    mm_per_unit, key = ellipse_scale(field)
    text = svg_text(out)
    assert f"one scale: a semi-axis of 1 {unit} drawn {mm_per_unit:.3g} mm long" in " ".join(text.split())
    assert f"key: {key:g} {unit}" in text
    assert f"{field.outside} lattice points outside the workspace, {field.singular} singular" in text


def test_several_views_in_one_run_are_the_single_views_figures_and_share_their_map(capsys, tmp_path, monkeypatch):
    """``--view map,bands,compare,pose``: one file per view, pixel for pixel what each view's own run
    writes, from one map of the current design (map, bands and compare share the grid) and one of the
    reference; the pose view computes none."""
    import app.cli.figure as figure_cli
    grids = []

    def counted(mechanism, grid, quantities, **kwargs):
        grids.append(grid)
        return compute_map(mechanism, grid, quantities, **kwargs)

    monkeypatch.setattr(figure_cli, "compute_map", counted)
    common = ["fivebar_singh", "--resolution", "41", "--size", "400x300", "--set", "proximal=80"]
    views = ("map", "bands", "compare", "pose")
    status, err = figure(capsys, *common, "--view", ",".join(views), "--out", str(tmp_path / "all_{view}.png"))
    assert status == 0, err
    assert err.splitlines() == [f"wrote {tmp_path / f'all_{v}.png'}" for v in views]
    assert len(grids) == 2 and grids[0] == grids[1] == load_preset("fivebar_singh").grid.with_resolution(41)
    for view in views:
        status, err = figure(capsys, *common, "--view", view, "--out", str(tmp_path / f"one_{view}.png"))
        assert status == 0, err
        batch, alone = (matplotlib.image.imread(tmp_path / f"{w}_{view}.png") for w in ("all", "one"))
        np.testing.assert_array_equal(batch, alone, err_msg=view)


def test_several_views_are_written_all_or_none(capsys, tmp_path, monkeypatch):
    """A view that fails after others were drawn leaves none of the run's files, and an older
    file of the same name as it was; the run is one line naming the view, exit status 2."""
    import app.cli.figure as figure_cli
    drawn = []

    def export_view(view, path, **kwargs):
        if view == "bands":
            raise ValueError("the bands could not be drawn")
        drawn.append(view)
        path.write_bytes(b"new")
        return path

    monkeypatch.setattr(figure_cli, "export_view", export_view)
    old = tmp_path / "f_map.png"
    old.write_bytes(b"old")
    status, err = figure(capsys, "fivebar_singh", "--resolution", "21", "--view", "map,pose,bands",
                         "--out", str(tmp_path / "f_{view}.png"))
    assert status == 2 and drawn == ["map", "pose"]
    assert err.count("\n") == 1 and "--view bands: the bands could not be drawn; no file written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f_map.png"] and old.read_bytes() == b"old"


# -- bad input -------------------------------------------------------------------------------
@pytest.mark.parametrize("argv, phrase", [
    (["fivebar_singh", "--view", "bogus", "--out", "{tmp}/m.png"], "--view: unknown view 'bogus'"),
    (["fivebar_singh", "--view", "map,bogus", "--out", "{tmp}/m_{view}.png"], "--view: unknown view 'bogus'"),
    (["fivebar_singh", "--view", ",", "--out", "{tmp}/m.png"], "--view"),
    (["fivebar_singh", "--view", "map,pose", "--out", "{tmp}/m.png"], "--out needs {view}"),
    (["fivebar_singh", "--view", "map,ellipses", "--spacing", "0.5", "--out", "{tmp}/{view}.png"], "larger spacing"),
    # A 3D box map's flat views are drawn on a plane (issue 21): a plane outside the box is refused.
    (["novint_falcon", "--view", "map,bands", "--plane", "z=20", "--out", "{tmp}/{view}.png"],
     "--plane z=20: z = 20 mm is outside the map's box"),
    (["novint_falcon", "--view", "workspace", "--plane", "z=110", "--out", "{tmp}/w.png"],
     "--plane applies to --view map, compare, bands, ellipses only"),
    (["inverse3_prototype", "--view", "pose", "--quantity", "torque_bias", "--out", "{tmp}/p.png"],
     "not one number per point"),
    (["fivebar_singh", "--out", "{tmp}/map.jpg"], "--out must end in .png, .svg or .pdf"),
    (["fivebar_singh", "--out", "{tmp}/missing/map.png"], "does not exist"),
    (["fivebar_singh", "--view", "pose", "--glyphs", "links,halo", "--out", "{tmp}/p.png"], "--glyphs"),
    (["fivebar_singh", "--view", "pose", "--force", "1,2,3", "--out", "{tmp}/p.png"], "--force needs 2"),
    (["fivebar_singh", "--size", "10x10", "--out", "{tmp}/m.png"], "--size"),
    (["inverse3_prototype", "--quantity", "singularity", "--out", "{tmp}/m.png"], "--quantity"),
    (["inverse3_prototype", "--view", "pose", "--at", "1,2", "--out", "{tmp}/p.png"], "--at needs X,Y,Z"),
    (["no_such_device", "--out", "{tmp}/m.png"], "DEVICE"),
    (["fivebar_singh", "--set", "proximal=-5", "--out", "{tmp}/m.png"], "--set"),
    (["inverse3_prototype", "--view", "ellipses", "--out", "{tmp}/e.png"], "needs a planar device"),
    (["fivebar_singh", "--view", "ellipses", "--spacing", "0", "--out", "{tmp}/e.png"], "--spacing needs a positive"),
    (["fivebar_singh", "--view", "ellipses", "--spacing", "0.5", "--out", "{tmp}/e.png"], "larger spacing"),
    (["fivebar_singh", "--view", "ellipses", "--spacing", "ten", "--out", "{tmp}/e.png"], "--spacing"),
    (["fivebar_singh", "--view", "ellipses", "--ellipse", "torque", "--out", "{tmp}/e.png"], "--ellipse"),
    (["fivebar_singh", "--view", "bands", "--spacing", "10", "--out", "{tmp}/b.png"], "--spacing applies to"),
    (["fivebar_singh", "--view", "map", "--ellipse", "force", "--out", "{tmp}/b.png"], "--ellipse applies to"),
    (["novint_falcon", "--view", "bands", "--plane", "q=1", "--out", "{tmp}/b.png"], "--plane: axis 'q'"),
    # An option no asked-for view uses would be ignored without a word (audit): refused.
    (["fivebar_singh", "--view", "map", "--at", "0,150", "--out", "{tmp}/m.png"], "--at applies to --view pose only"),
    (["fivebar_singh", "--force", "1,2", "--out", "{tmp}/m.png"], "--force applies to --view pose only"),
    (["fivebar_singh", "--view", "workspace", "--glyphs", "links", "--out", "{tmp}/w.png"], "--glyphs applies to"),
    (["inverse3_prototype", "--compare", "difference", "--out", "{tmp}/m.png"], "--compare applies to --view compare"),
    (["inverse3_prototype", "--view", "compare", "--out", "{tmp}/c.png"], "without --set there is nothing to compare"),
])
def test_bad_input_is_one_line_naming_the_argument_and_writes_nothing(capsys, tmp_path, argv, phrase):
    status, err = figure(capsys, *[a.replace("{tmp}", str(tmp_path)) for a in argv])
    assert status == 2
    assert err.count("\n") == 1 and err.startswith("isoforce") and "Traceback" not in err
    assert phrase in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_pose_figure_has_the_views_legend_of_glyphs(capsys, tmp_path, svg_text_as_text):
    """A printed pose figure names each glyph's colour, as the app's view does (a reader could
    not tell the polytope from the sphere, nor the actuators' arrows apart: found by the
    audit); a swatch of the colours is in the figure."""
    out = tmp_path / "pose.svg"
    status, err = figure(capsys, "fivebar_singh", "--view", "pose", "--at", "40,170", "--force", "300,-50",
                         "--size", "800x600", "--out", str(out))
    assert status == 0, err
    text = " ".join(svg_text(out).split())
    names = ["links", "force polytope", "inscribed sphere", "theta_1 at full torque", "theta_2 at full torque",
             "desired force", "clamped force"]
    assert all(name in text for name in names), text
    png = tmp_path / "pose.png"
    status, err = figure(capsys, "fivebar_singh", "--view", "pose", "--at", "40,170", "--force", "300,-50",
                         "--size", "800x600", "--out", str(png))
    assert status == 0, err
    # The polytope's swatch is the colour it shows (issue 26): translucent over the white, the same
    # in the legend and over the picture's polytope (its base colour appears nowhere).
    swatch = seen_colour(scenes.COLOURS["polytope"], FLAT_OPACITY)
    assert colour_pixels(png, swatch) > 200 and colour_pixels(png, scenes.COLOURS["polytope"]) == 0
