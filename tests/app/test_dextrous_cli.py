"""``isoforce dextrous``: the JSON equals ``metrics.dextrous``, bad input exits 2 with one line, ``--out`` is atomic."""
from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib.image
import matplotlib.text
import numpy as np
import pytest
from matplotlib.colors import to_rgb

import app.cli.dextrous as cli
import app.scenes.dextrous_figure as figure
from app.cli import main
from metrics.dextrous import box_grid, dextrous_region
from metrics.dextrous_orientations import orientation_set
from resources import load_preset

ROOT = Path(__file__).resolve().parents[2]
STEWART = str(ROOT / "docs" / "dextrous" / "stewart_fig13.toml")
TWIN = str(ROOT / "docs" / "dextrous" / "twin_pantograph_fig13.toml")
SMALL = ("--resolution", "7", "--angle", "20")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    capsys.readouterr()
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *argv: str) -> dict:
    status, out, err = run(capsys, "dextrous", *argv, "--json")
    assert status == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def test_json_shape_and_numbers_equal_the_compute_layer(capsys):
    doc = run_json(capsys, STEWART, TWIN, *SMALL, "--box", "-200,200,-200,200,0,240")
    assert set(doc) == {"devices", "definitions", "units"}
    assert doc["units"] == {"volume": "cm^3", "length": "mm", "angle": "deg"}
    assert [d["key"] for d in doc["devices"]] == ["stewart_fig13", "twin_pantograph_fig13"]
    for row, path in zip(doc["devices"], (STEWART, TWIN)):
        mech = load_preset(path).mechanism
        grid = box_grid((-0.2, -0.2, 0.0), (0.2, 0.2, 0.24), 7)
        region = dextrous_region(mech, grid, orientation_set(mech, math.radians(20)))
        assert row["volume_cm3"] == pytest.approx(region.volume.value * 1e6, rel=1e-12)
        assert row["volume_error_cm3"] == pytest.approx(region.volume.error * 1e6, rel=1e-12)
        assert row["reachable_volume_cm3"] == pytest.approx(region.reachable_volume.value * 1e6, rel=1e-12)
        assert row["points_inside"] == int(region.inside.sum())
        assert row["box_mm"] == {"x": [-200.0, 200.0], "y": [-200.0, 200.0], "z": [0.0, 240.0]}
        assert row["resolution"] == [7, 7, 7] and row["angle_deg"] == pytest.approx(20.0)
        assert row["orientations"]["count"] == region.orientations.count
        assert isinstance(row["clipped"], bool)
    assert doc["devices"][0]["ujoint_limit_deg"] is None               # the Stewart has no U-joint limit
    assert doc["devices"][1]["ujoint_limit_deg"] == pytest.approx(85.0)


def test_ujoint_limit_option_reaches_the_model_and_only_models_with_one(capsys):
    doc = run_json(capsys, STEWART, TWIN, *SMALL, "--ujoint-limit", "60")
    stewart, twin = doc["devices"]
    assert stewart["ujoint_limit_deg"] is None and twin["ujoint_limit_deg"] == pytest.approx(60.0)
    mech = load_preset(TWIN).mechanism.replace_display(ujoint_limit=60.0)
    grid = box_grid(*cli.default_box(load_preset(TWIN)), 7)
    region = dextrous_region(mech, grid, orientation_set(mech, math.radians(20)))
    assert twin["points_inside"] == int(region.inside.sum())


def test_text_output_labels_units_and_the_error(capsys):
    status, out, err = run(capsys, "dextrous", "twin_pantograph", *SMALL)
    assert status == 0, err
    assert "semi-dextrous volume (cm^3)" in out and "+-" in out and "boundary-cell estimate" in out
    assert "roll free" in out                     # alone, the 5-DOF preset is taken as it is
    assert "grown 1 time from the map range" in out   # its region reaches past its map's range


def test_a_clipped_volume_is_printed_as_a_lower_bound(capsys):
    """The shipped Twin-Pantograph's region reaches past its map's range: with that box fixed by --box its
    volume is printed ">= V (clipped by the box)", never with a +- as if it were the volume."""
    box = ("--box", "-150,150,-185,185,50,420")
    status, out, err = run(capsys, "dextrous", "twin_pantograph", *SMALL, *box)
    assert status == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("twin_pantograph "))
    assert ">= " in line and "(clipped by the box)" in line and "+-" not in line.split("(clipped")[0]
    assert "lower bound" in out
    row = run_json(capsys, "twin_pantograph", *SMALL, *box)["devices"][0]
    assert row["clipped"] and row["volume_is_lower_bound"] and row["box_grew_rounds"] == 0
    assert row["reachable_volume_is_lower_bound"] == row["reachable_clipped"]


def test_a_default_box_grows_until_the_region_is_whole(capsys):
    """Without --box the box starts at the map range and its touched faces move out, the spacing kept, until
    the region does not touch it: the volume is then the region's, equal to a run on the grown box."""
    row = run_json(capsys, "twin_pantograph", *SMALL)["devices"][0]
    assert row["box_grew_rounds"] >= 1 and not row["clipped"] and not row["volume_is_lower_bound"]
    lower, upper = cli.default_box(load_preset("twin_pantograph"))
    box = row["box_mm"]
    for k, a in enumerate("xyz"):
        assert box[a][0] <= lower[k] * 1e3 + 1e-9 and box[a][1] >= upper[k] * 1e3 - 1e-9
        spacing = (upper[k] - lower[k]) / 6 * 1e3                   # 7 points on the map range
        assert (box[a][1] - box[a][0]) / (row["resolution"][k] - 1) == pytest.approx(spacing, rel=1e-9)
    mech = load_preset("twin_pantograph").mechanism
    grid = box_grid([box[a][0] / 1e3 for a in "xyz"], [box[a][1] / 1e3 for a in "xyz"], tuple(row["resolution"]))
    region = dextrous_region(mech, grid, orientation_set(mech, math.radians(20)))
    assert row["points_inside"] == int(region.inside.sum()) and not region.clipped


def test_like_with_like_takes_a_roll_free_pen_in_its_6_dof_version(capsys):
    """Beside a 6-DOF platform the 5-DOF, roll-free Twin-Pantograph is tested as its 6-DOF version (roll
    actuated, waist q4 passive: paper 001 Table III) and says so; --as-is keeps the preset's own task."""
    box = ("--box", "-200,200,-200,200,100,400")
    doc = run_json(capsys, "stewart_platform", "twin_pantograph", *SMALL, *box)
    stewart, twin = doc["devices"]
    assert stewart["changed"] is None and twin["task"] == ["x", "y", "z", "rx", "ry", "rz"]
    assert "6-DOF version" in twin["changed"] and not twin["orientations"]["roll_free"]
    mech = load_preset("twin_pantograph").mechanism.replace(**cli.SIX_DOF)
    region = dextrous_region(mech, box_grid((-0.2, -0.2, 0.1), (0.2, 0.2, 0.4), 7),
                             orientation_set(mech, math.radians(20)))
    assert twin["points_inside"] == int(region.inside.sum())
    as_is = run_json(capsys, "stewart_platform", "twin_pantograph", *SMALL, *box, "--as-is")["devices"][1]
    assert as_is["task"] == ["x", "y", "z", "rx", "rz"] and as_is["changed"] is None
    assert as_is["orientations"]["roll_free"]
    status, out, _ = run(capsys, "dextrous", "stewart_platform", "twin_pantograph", *SMALL, *box)
    assert status == 0 and "twin_pantograph is its 6-DOF version" in out


def test_devices_of_one_kind_are_not_changed():
    presets = [load_preset("twin_pantograph"), load_preset("twin_pantograph_prototype")]
    out, notes = cli.like_with_like(presets)
    assert notes == [None, None] and [p.mechanism for p in out] == [p.mechanism for p in presets]


def test_default_box_fills_the_fixed_axis():
    lower, upper = cli.default_box(load_preset("stewart_platform"))
    assert lower == pytest.approx((-0.12, -0.12, 0.15)) and upper == pytest.approx((0.12, 0.12, 0.33))


@pytest.mark.parametrize("argv,phrases", [
    (["stewart_platform", "--angle", "0"], ["--angle", "(0, 90]"]),
    (["stewart_platform", "--angle", "95"], ["--angle"]),
    (["stewart_platform", "--angle", "nan"], ["--angle"]),
    (["stewart_platform", "--ujoint-limit", "100"], ["--ujoint-limit"]),
    (["stewart_platform", "--box", "1,2,3"], ["--box", "X0,X1"]),
    (["stewart_platform", "--box", "0,-1,0,1,0,1"], ["--box"]),
    (["stewart_platform", "--resolution", "2"], ["--resolution"]),
    (["stewart_platform", "--rings", "0"], ["--rings"]),
    (["no_such_device"], ["DEVICE"]),
    (["fivebar_singh"], ["fivebar_singh", "task coordinates"]),
    (["stewart_platform", "twin_pantograph", "--set", "min_leg=80"], ["--set", "one DEVICE"]),
    (["stewart_platform", "--set", "min_leg=-1"], ["--set"]),
    (["stewart_platform", "--out", "region.jpg"], ["--out", ".png"]),
    (["stewart_platform", "--size", "10x10", "--out", "region.png"], ["--size"]),
])
def test_bad_arguments_exit_2_with_one_line(capsys, tmp_path, monkeypatch, argv, phrases):
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "dextrous", *argv)
    assert status == 2, (out, err)
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("isoforce"), err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    assert list(tmp_path.iterdir()) == []                       # no file, no temporary


def test_a_bad_out_is_refused_before_computing(capsys, monkeypatch, tmp_path):
    def boom(*args, **kwargs):
        raise AssertionError("computed before checking --out")

    monkeypatch.setattr(cli, "dextrous_region", boom)
    status, _, err = run(capsys, "dextrous", STEWART, "--out", str(tmp_path / "missing" / "a.png"))
    assert status == 2 and "--out" in err


def test_too_big_a_grid_is_refused_before_computing(capsys, monkeypatch):
    monkeypatch.setenv("ISOFORCE_MEMORY", "64M")
    monkeypatch.setattr(cli, "dextrous_region", lambda *a, **k: pytest.fail("computed a job that cannot fit"))
    status, _, err = run(capsys, "dextrous", STEWART, "--resolution", "2000")
    assert status == 2 and "--resolution" in err and "available" in err


def _has_colour(image: np.ndarray, colour: str, tol: float = 0.25) -> int:
    """Pixels whose RGB is within ``tol`` of ``colour`` in hue direction (shading darkens the surface)."""
    rgb = image[..., :3].reshape(-1, 3)
    target = np.asarray(to_rgb(colour))
    norm = np.linalg.norm(rgb, axis=1, keepdims=True)
    cos = (rgb / np.maximum(norm, 1e-9)) @ (target / np.linalg.norm(target))
    return int(np.count_nonzero((cos > 1 - tol * 0.1) & (norm[:, 0] > 0.2)))


def test_out_writes_a_comparison_figure_atomically(capsys, tmp_path):
    out = tmp_path / "cmp.png"
    status, _, err = run(capsys, "dextrous", STEWART, TWIN, *SMALL, "--out", str(out), "--size", "800x400")
    assert status == 0, err
    assert [p.name for p in tmp_path.iterdir()] == ["cmp.png"]    # no temporary left
    image = matplotlib.image.imread(out)
    assert image.shape[:2] == (400, 800)
    # Both panels show a region: the region's blue in the left and in the right half.
    assert _has_colour(image[:, :400], figure.REGION_COLOUR) > 50
    assert _has_colour(image[:, 400:], figure.REGION_COLOUR) > 50


@pytest.mark.parametrize("suffix,magic", [(".svg", b"<"), (".pdf", b"%PDF-")])
def test_out_vector_formats(capsys, tmp_path, suffix, magic):
    out = tmp_path / f"region{suffix}"
    status, _, err = run(capsys, "dextrous", STEWART, "--resolution", "5", "--angle", "10", "--out", str(out))
    assert status == 0, err
    data = out.read_bytes()
    assert data.lstrip().startswith(magic)
    assert [p.name for p in tmp_path.iterdir()] == [out.name]


def test_a_failed_render_leaves_the_old_file_and_no_temporary(capsys, tmp_path, monkeypatch):
    import app.scenes.snapshot as snapshot
    out = tmp_path / "region.png"
    out.write_bytes(b"old figure")

    def fail(fname, *args, **kwargs):
        Path(fname).write_bytes(b"partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(snapshot, "imsave", fail)
    status, _, err = run(capsys, "dextrous", STEWART, "--resolution", "5", "--angle", "10", "--out", str(out))
    assert status == 2 and "No space left on device" in err
    assert out.read_bytes() == b"old figure"
    assert [p.name for p in tmp_path.iterdir()] == ["region.png"]


def test_region_mesh_is_closed_and_in_mm():
    mech = load_preset(STEWART).mechanism
    grid = box_grid((-0.12, -0.12, 0.0), (0.12, 0.12, 0.24), 13)
    region = dextrous_region(mech, grid, orientation_set(mech, math.radians(30)))
    pos = region.positions() * 1e3
    lo, hi = pos.min(0), pos.max(0)
    h = np.asarray(grid.spacing()) * 1e3
    # The raw 0.5 iso-surface cuts every inside-outside edge at its midpoint: half a cell outside the
    # outermost inside points (to rounding of the mm coordinates, ~1e-13 mm).
    raw = np.asarray(figure.region_mesh(region, smooth=0).bounds).reshape(3, 2)
    np.testing.assert_allclose(raw[:, 0], lo - h / 2, atol=1e-9)
    np.testing.assert_allclose(raw[:, 1], hi + h / 2, atol=1e-9)
    # Smoothing moves it by less than half a cell, and it stays closed.
    mesh = figure.region_mesh(region)
    b = np.asarray(mesh.bounds).reshape(3, 2)
    assert np.all(np.abs(b - raw) < h[:, None] / 2)
    assert mesh.n_points > 0 and mesh.n_open_edges == 0


def test_figure_caption_says_a_clipped_volume_is_a_lower_bound():
    mech = load_preset(STEWART).mechanism
    whole = dextrous_region(mech, box_grid((-0.12, -0.12, 0.0), (0.12, 0.12, 0.24), 9),
                            orientation_set(mech, math.radians(30)))
    cut = dextrous_region(mech, box_grid((-0.08, -0.08, 0.06), (0.08, 0.08, 0.2), 9),
                          orientation_set(mech, math.radians(30)))
    assert not whole.clipped and cut.reachable_clipped
    assert "+-" in figure.caption(whole).splitlines()[0] and ">=" not in figure.caption(whole).splitlines()[0]
    reach_line = figure.caption(cut).splitlines()[1]
    assert reach_line.startswith("reachable at zero orientation: >= ") and "(clipped by the box)" in reach_line


def _regions():
    mech = load_preset(STEWART).mechanism
    grid = box_grid((-0.12, -0.12, 0.0), (0.12, 0.12, 0.24), 9)
    return [dextrous_region(mech, grid, orientation_set(mech, math.radians(30)))] * 2


@pytest.mark.parametrize("kwargs", [{}, {"size": (800, 400)}, {"column": (3.5, 8.0)}])
def test_the_figures_texts_are_whole_apart_and_inside_it(kwargs):
    """The title's lines, each panel's volumes, the scale bar and the key: every text inside the
    figure and none over another (VTK's cube axes wrote "-320.0" over "-555.0" and the title lost
    its second line in the PDF)."""
    titles = ["Stewart platform (paper 001 comparison)\nU-joints +-85 deg", "Stewart again\nU-joints +-60 deg"]
    composed = figure.dextrous_figure(_regions(), titles, **kwargs)
    fig = composed.figure
    renderer = fig.canvas.get_renderer()
    texts = [t for t in fig.findobj(matplotlib.text.Text) if t.get_text() and t.get_visible()]
    shown = " ".join(t.get_text() for t in texts)
    assert all(line in shown for title in titles for line in title.splitlines())
    boxes = [t.get_window_extent(renderer) for t in texts]
    page = fig.bbox
    for text, box in zip(texts, boxes):
        assert page.x0 - 0.5 <= box.x0 <= box.x1 <= page.x1 + 0.5, text.get_text()
        assert page.y0 - 0.5 <= box.y0 <= box.y1 <= page.y1 + 0.5, text.get_text()
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            assert not boxes[i].overlaps(boxes[j]), (texts[i].get_text(), texts[j].get_text())
    if "column" in kwargs:
        assert fig.get_size_inches()[0] == pytest.approx(3.5)
        sizes = [t.get_fontsize() for t in texts if "deg:" in t.get_text()]
        assert sizes and sizes == pytest.approx([8.0] * len(sizes))


def test_the_figure_prints_volumes_with_the_digits_their_error_supports(capsys, tmp_path):
    """``49000 +- 5000 cm^3``, not ``49420 +- 4800`` nor ``3.046e+04``: the table and the figure alike."""
    from app.logic.volume_digits import volume_with_error
    row = run_json(capsys, TWIN, *SMALL)["devices"][0]
    value, error = volume_with_error(row["volume_cm3"], row["volume_error_cm3"])
    status, out, err = run(capsys, "dextrous", TWIN, *SMALL)
    assert f"{value} +- {error}" in out
    svg = tmp_path / "r.svg"
    status, out, err = run(capsys, "dextrous", TWIN, *SMALL, "--out", str(svg))
    assert status == 0, err
    text = svg.read_text()
    assert f"{value} +- {error} cm^3" in text and "e+0" not in text.split("</metadata>")[-1]


def test_growing_box_ends_with_the_region_of_whole_regions_grown_each_round(capsys):
    """``device_region`` leaves a box after its face points (``face_test``): it ends where growing by each
    whole region's ``clipped_faces`` ends, with the same region and pose count."""
    from argparse import Namespace

    from metrics.dextrous import clipped_faces, grown_grid

    preset = load_preset("twin_pantograph")
    args = Namespace(ujoint_limit=None, rings=None, rolls=None, resolution=7)
    _, region, _, rounds = cli.device_region(preset, args, math.radians(20), None)
    mech = preset.mechanism
    orient = orientation_set(mech, math.radians(20))
    grid = box_grid(*cli.default_box(preset), 7)
    want, want_rounds = dextrous_region(mech, grid, orient), 0
    while want.clipped and want_rounds < cli.GROW_ROUNDS:
        grid, want_rounds = grown_grid(grid, clipped_faces(want.inside)), want_rounds + 1
        want = dextrous_region(mech, grid, orient)
    assert rounds == want_rounds >= 1 and region.grid == want.grid
    np.testing.assert_array_equal(region.inside, want.inside)
    np.testing.assert_array_equal(region.reachable, want.reachable)
    assert region.poses_evaluated == want.poses_evaluated


# -- start-up: what a run imports ---------------------------------------------------------------
LOADED = r"""
import json, sys
PRELOAD
from app.cli import main
status = main(sys.argv[1:])
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""
#: Libraries a run without ``--out`` has no use for: numba (0.44 s to import) serves the map kernels,
#: the rest draw (``--out`` loads them).
UNUSED_LIBRARIES = {"numba", "llvmlite", "scipy", "matplotlib", "pyvista", "vtk", "vtkmodules", "PySide6"}
#: The map's machinery (quantity graph, kernels, statistics), which a region does not use.
UNUSED_MODULES = {"metrics.quantities", "metrics.workspace", "metrics.map_chunks", "metrics.kernels",
                  "metrics.statistics", "metrics.polytopes", "resources.study_schema"}


def modules_of_a_run(argv: list[str], preload: str = "") -> set[str]:
    """The modules a fresh interpreter holds after ``isoforce *argv`` (which must succeed)."""
    import subprocess
    import sys

    script = LOADED.replace("PRELOAD", preload)
    result = subprocess.run([sys.executable, "-c", script, *argv], cwd=ROOT, capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["status"] == 0
    return set(report["modules"])


def unwanted(modules: set[str], kind: str) -> list[str]:
    """Modules of ``modules`` a run on a ``kind`` device should not have imported."""
    from kinematics.registry import _WHERE

    others = {f"kinematics.{module}" for k, (module, _) in _WHERE.items() if k != kind}
    return sorted((modules & (UNUSED_MODULES | others)) | ({m.split(".")[0] for m in modules} & UNUSED_LIBRARIES))


def test_a_run_imports_neither_numba_nor_the_map_nor_other_models():
    """``isoforce dextrous DEVICE --json`` imports its model and the region's modules: not numba, scipy or
    a plotting library, not the map's quantity graph or kernels, not the other six models."""
    modules = modules_of_a_run(["dextrous", "twin_pantograph", "--resolution", "7", "--json"])
    assert "metrics.dextrous" in modules and "kinematics.twin_pantograph" in modules
    assert unwanted(modules, "twin_pantograph") == []


def test_the_start_up_check_can_fail():
    """The same check sees numba's kernels, the map and another model when a run has them (the script
    imports them before the command)."""
    modules = modules_of_a_run(["dextrous", "twin_pantograph", "--resolution", "5", "--json"],
                               "import numba, metrics.workspace, kinematics.delta")
    assert {"numba", "metrics.workspace", "metrics.quantities", "kinematics.delta"} <= set(
        unwanted(modules, "twin_pantograph"))
