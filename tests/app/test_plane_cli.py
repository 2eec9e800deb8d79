"""Issue 21 section 1: figures of a device with a 3D box map (the Novint Falcon) on one plane of it.

``isoforce map`` and ``isoforce figure`` draw the plane ``--plane AXIS=MM`` names (default: the
preset's, the one the app opens on), snapped to the nearest grid plane and named; the plane's
values are checked against the whole volume ``compute_map`` returns, indexed by hand. Bad planes
get an error naming ``--plane``; no internal message reaches the user.
"""
from __future__ import annotations

import numpy as np
import pytest

from app.cli import main as cli_main
from app.logic.colour_scale import COLOUR_RANGES, plane_scale
from app.logic.planes import default_plane, parse_plane, plane_text, volume_slice
from app.plots.figures import map_figure
from app.render.views import FLAT_VIEWS, export_view
from metrics.workspace import compute_map
from resources import load_preset

FALCON = "novint_falcon"
#: Internal texts that must never reach a user (ValueErrors of the figure layer on a volume).
INTERNAL = ("wmap must", "Traceback", "got axes", "needs a 2D map")


@pytest.fixture(scope="module")
def falcon():
    preset = load_preset(FALCON)
    grid = preset.grid.with_resolution((13, 13, 12))
    return preset, grid, compute_map(preset.mechanism, grid, ("isotropic_force", "condition_number",
                                                                 "anisotropic_force"))


def run(args, capsys):
    code = cli_main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_isoforce_map_draws_the_presets_plane_by_default(tmp_path, capsys):
    preset = load_preset(FALCON)
    out = tmp_path / "f.png"
    code, text, err = run(["map", FALCON, "--quantity", "isotropic_force", "--out", str(out)], capsys)
    assert code == 0, err
    assert out.stat().st_size > 1000
    axis, value = default_plane(preset.grid, preset.mechanism, preset.pose)
    # The preset's pose is at z = 110 mm, on the grid plane 18 of 37 (30 + 18 * 160 / 36 mm).
    assert (axis, value) == ("z", pytest.approx(0.110))
    assert "plane z = 110 mm" in text and "nearest" not in text


def test_plane_data_are_the_volumes_plane_and_a_snapped_plane_is_named(tmp_path, capsys):
    preset = load_preset(FALCON)
    grid = preset.grid.with_resolution(13)
    z = grid.coordinates()[2]
    asked = float(0.6 * z[5] + 0.4 * z[4])        # nearer plane 5 than 4
    out = tmp_path / "plane.npz"
    code, text, err = run(["map", FALCON, "--quantity", "isotropic_force", "--resolution", "13",
                           "--plane", f"z={asked * 1e3!r}", "--out", str(out)], capsys)
    assert code == 0, err
    assert f"plane z = {z[5] * 1e3:.4g} mm (nearest grid plane to {asked * 1e3:.4g} mm)" in text
    stored = np.load(out)["isotropic_force"]
    full = compute_map(preset.mechanism, grid, ("isotropic_force",))
    values, feasible = full.values["isotropic_force"][:, :, 5], full.feasible[:, :, 5]
    assert stored.shape == (13, 13) and feasible.any()
    np.testing.assert_allclose(stored[feasible], values[feasible], rtol=1e-12)


def test_data_of_a_volume_without_plane_stay_the_whole_volume(tmp_path, capsys):
    out = tmp_path / "volume.npz"
    code, text, err = run(["map", FALCON, "--quantity", "isotropic_force", "--resolution", "9", "--out", str(out)],
                          capsys)
    assert code == 0, err
    assert np.load(out)["isotropic_force"].shape == (9, 9, 9)
    assert "plane" not in text


@pytest.mark.parametrize("plane, says", [
    ("z=300", "outside the map's box, z from 30 to 190 mm"),
    ("x=-95", "outside the map's box, x from -90 to 90 mm"),
    ("w=10", "axis 'w' is not one of the box's axes x, y, z"),
    ("z", "needs AXIS=POSITION"),
    ("z=nan", "needs AXIS=POSITION"),
])
@pytest.mark.parametrize("command", ["map", "figure"])
def test_a_bad_plane_gets_an_error_naming_plane(command, plane, says, tmp_path, capsys):
    args = ([command, FALCON, "--quantity", "isotropic_force", "--out", str(tmp_path / "f.png"), "--plane", plane])
    code, _, err = run(args, capsys)
    assert code == 2
    assert "--plane" in err and says in err
    assert not any(text in err for text in INTERNAL)
    assert not (tmp_path / "f.png").exists()


def test_plane_on_a_slice_device_is_refused_naming_plane(tmp_path, capsys):
    code, _, err = run(["map", "fivebar_singh", "--quantity", "isotropic_force", "--plane", "z=0",
                        "--out", str(tmp_path / "f.png")], capsys)
    assert code == 2 and "--plane applies to a 3D box map" in err


def test_every_flat_figure_view_of_a_volume_device_is_written(tmp_path, capsys):
    out = tmp_path / "f_{view}.png"
    code, text, err = run(["figure", FALCON, "--view", "map,bands,compare", "--plane", "y=20", "--resolution", "15",
                           "--set", "gear_ratios=9,9,9", "--out", str(out)], capsys)
    assert code == 0, err
    for view in ("map", "bands", "compare"):
        assert (tmp_path / f"f_{view}.png").stat().st_size > 1000
    grid = load_preset(FALCON).grid.with_resolution(15)
    y = grid.coordinates()[1]
    at = y[int(np.argmin(np.abs(y - 0.020)))]
    assert text.count(f"plane y = {at * 1e3:.4g} mm (nearest grid plane to 20 mm)") == 3
    # The ellipses view applies to planar devices only: refused with the reason, not an internal error.
    code, _, err = run(["figure", FALCON, "--view", "ellipses", "--out", str(tmp_path / "e.png")], capsys)
    assert code == 2 and "planar device" in err and not any(t in err for t in INTERNAL)


@pytest.mark.parametrize("view", FLAT_VIEWS)
def test_export_view_draws_a_volume_on_the_plane_asked(falcon, view, tmp_path):
    """The app's exports hand the volume and the plane on screen to ``export_view``: every flat view
    that applies draws that plane; the one that does not (ellipses: a spatial device) says why."""
    preset, grid, volume = falcon
    plane = ("x", float(grid.coordinates()[0][7]))
    kwargs = dict(preset=preset, mechanism=preset.mechanism, workspace_map=volume, quantity="isotropic_force",
                  reference_map=volume, plane=plane)
    if view == "ellipses":
        with pytest.raises(ValueError, match="planar") as info:
            export_view(view, tmp_path / f"{view}.png", **kwargs)
        assert not any(text in str(info.value) for text in INTERNAL)
        return
    assert export_view(view, tmp_path / f"{view}.png", **kwargs).stat().st_size > 1000


@pytest.mark.parametrize("colour_range", list(COLOUR_RANGES))
def test_the_exported_plane_is_the_volumes_plane_in_the_range_named(falcon, colour_range):
    preset, grid, volume = falcon
    k = 6
    plane = volume_slice(volume, "z", float(grid.coordinates()[2][k]))
    fig = map_figure(plane, "isotropic_force", preset,
                     scale=plane_scale(volume, plane, "isotropic_force", preset, colour_range))
    image = fig.axes[0].images[0]
    data = image.get_array().T
    values, feasible = volume.values["isotropic_force"][:, :, k], volume.feasible[:, :, k]
    np.testing.assert_array_equal(~np.ma.getmaskarray(data), feasible & np.isfinite(values))
    np.testing.assert_array_equal(np.ma.getdata(data)[feasible], values[feasible])
    source = volume if colour_range == "volume" else plane
    finite = source.values["isotropic_force"][source.feasible & np.isfinite(source.values["isotropic_force"])]
    lo, hi = image.get_clim()
    # Lower limit: the smallest value of the range drawn (the upper may be capped at a percentile).
    assert lo == finite.min() and hi <= finite.max()
    assert COLOUR_RANGES[colour_range] in fig.axes[1].get_ylabel()
    assert "z = " in fig.axes[0].get_title()


def test_parse_plane_takes_the_box_ends_and_plane_text_names_the_snap():
    preset = load_preset(FALCON)
    grid, mech = preset.grid, preset.mechanism
    assert parse_plane("z=190", grid, mech) == ("z", pytest.approx(0.19))
    assert parse_plane(" x = -90 ", grid, mech) == ("x", pytest.approx(-0.09))
    assert plane_text(grid, "z", 0.110, mech) == "plane z = 110 mm"
    assert plane_text(grid, "z", 0.112, mech) == "plane z = 110 mm (nearest grid plane to 112 mm)"
