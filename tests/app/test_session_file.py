"""Session files (``app.files.session``), without a display: a round trip gives back every field,
a bad file gets one ``SessionError`` naming the file and the key, and ``isoforce figure
--session`` draws from it or refuses it in one line."""
from __future__ import annotations

import numpy as np
import pytest

from app.cli import main
from app.files.session import Session, SessionError, read_session, session_to_toml, write_session
from metrics.loading import Loading
from resources import load_preset


def test_a_session_round_trips_design_reference_views_plane_and_cameras(tmp_path):
    falcon = load_preset("novint_falcon")             # a 3D box map: it has a plane
    five = load_preset("fivebar_singh")
    mech = falcon.mechanism.replace_display(upper_arm=65.0)
    camera = dict(position=(0.3, -0.4, 0.5), focal_point=(0.0, 0.0, 0.1), view_up=(0.0, 0.0, 1.0),
                  view_angle=30.0, parallel_scale=0.12, parallel=True)
    session = Session(preset=falcon, mechanism=mech, quantity="condition_number", compare_mode="difference",
                      glyphs=frozenset({"links", "force_ellipsoid"}), pose=falcon.pose, desired_force=(1.0, 2.0, 0.5),
                      plane=("z", 0.01), colour_range="volume", loading=Loading(rating="continuous"),
                      reference_preset=five,
                      reference_mechanism=five.mechanism.replace_display(proximal=120.0),
                      cameras={"workspace": camera})
    path = write_session(tmp_path / "s.toml", session)
    back = read_session(path)
    assert back.preset.key == "novint_falcon" and back.mechanism == mech
    assert back.reference_preset.key == "fivebar_singh" and back.reference_mechanism == session.reference_mechanism
    assert (back.quantity, back.compare_mode, back.glyphs, back.desired_force, back.loading) == (
        session.quantity, session.compare_mode, session.glyphs, session.desired_force, session.loading)
    assert np.allclose(back.pose, session.pose, rtol=1e-12) and back.plane[0] == "z"
    assert back.colour_range == "volume"
    assert np.isclose(back.plane[1], 0.01, rtol=1e-12)
    assert back.cameras == {"workspace": camera}
    assert session_to_toml(back) == session_to_toml(session)


BASE = 'version = 1\n[design]\npreset = "fivebar_singh"\n'


@pytest.mark.parametrize("text, key, phrase", [
    ("version = 1\n[design\n", None, "not a TOML file"),
    ('version = 2\n[design]\npreset = "fivebar_singh"\n', "version", "reads session version 1, got 2"),
    ("version = 1\n", "design", "missing"),
    ('version = 1\n[design]\npreset = "no_such_device"\n', "design.preset", "no_such_device"),
    (BASE + "[design.values]\nlength = 3.0\n", "design.values.length", "has no such parameter"),
    (BASE + "[design.values]\nproximal = -5.0\n", "design.values.proximal", "proximal"),
    (BASE + "[design.values]\nproximal = true\n", "design.values.proximal", "needs a number"),
    (BASE + "[design.values]\nworking_mode = \"sideways\"\n", "design.values.working_mode", "must be one of"),
    (BASE + "[view]\npose = [\"a\", 1.0]\n", "view.pose", "needs a list of numbers"),
    (BASE + "[view]\nrating = \"peak\"\n", "view.rating", "no peak torque rating"),
    (BASE + "[view]\noverlay = \"stripes\"\n", "view.overlay", "must be one of none, bands"),
    (BASE + "[view]\nglyphs = [\"halo\"]\n", "view.glyphs", "unknown glyph 'halo'"),
    (BASE + "[view]\npose = [1.0]\n", "view.pose", "needs 2 numbers, got 1"),
    (BASE + "[view]\ngravity = \"sideways\"\n", "view.gravity", "must be off, one of"),
    (BASE + "[view.plane]\naxis = \"z\"\nmm = 3.0\n", "view.plane", "not a 3D box"),
    ('version = 1\n[design]\npreset = "novint_falcon"\n[view.plane]\naxis = "z"\nmm = 3.0\ncolour_range = "all"\n',
     "view.plane.colour_range", "must be one of plane, volume, got 'all'"),
    (BASE + "[view.map]\naxes = [\"y\", \"x\"]\nlower = [0, 0]\nupper = [1, 1]\n", "view.map.axes",
     "needs the preset's map axes ['x', 'y']"),
    (BASE + "[view.map]\naxes = [\"x\", \"y\"]\nlower = [0, 0]\n", "view.map", "needs lower and upper"),
    (BASE + "[view.map]\naxes = [\"x\", \"y\"]\nlower = [0, 9]\nupper = [1, 1]\n", "view.map.upper",
     "must exceed lower on axis 'y', got 9 >= 1"),
    (BASE + "[view.map]\naxes = [\"x\", \"y\"]\nlower = [0, 0]\nupper = [1, 1]\nresolution = [40, 1.5]\n",
     "view.map.resolution", "needs 2 whole numbers of points"),
    (BASE + "[view.map]\naxes = [\"x\", \"y\"]\nlower = [0, 0]\nupper = [1, 1]\nzoom = 2\n", "view.map.zoom",
     "unknown key"),
    (BASE + "[camera.pose]\nposition = [0, 0, 1]\n", "camera.pose.focal_point", "missing"),
    (BASE + "[camera.side]\n", "camera.side", "unknown key"),
    (BASE + "[extra]\n", "extra", "unknown key"),
])
def test_a_bad_session_is_one_error_naming_the_file_and_key(tmp_path, text, key, phrase):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SessionError) as info:
        read_session(path)
    message = str(info.value)
    assert message.startswith("session 'bad.toml': " + (f"key {key!r}: " if key else ""))
    assert phrase in message


def test_a_missing_session_is_one_error_too(tmp_path):
    with pytest.raises(SessionError, match="session 'none.toml': cannot be read"):
        read_session(tmp_path / "none.toml")


def test_figure_session_draws_and_a_bad_one_is_one_line(tmp_path, capsys):
    five = load_preset("fivebar_singh")
    path = write_session(tmp_path / "s.toml", Session(preset=five, mechanism=five.mechanism.replace_display(
        proximal=110.0), quantity="condition_number", overlay="bands", reference_mechanism=five.mechanism))
    out = tmp_path / "f_{view}.png"
    assert main(["figure", "--session", str(path), "--view", "map,compare", "--resolution", "30",
                 "--out", str(out)]) == 0
    for view in ("map", "compare"):
        assert (tmp_path / f"f_{view}.png").stat().st_size > 0
    capsys.readouterr()
    (tmp_path / "bad.toml").write_text(BASE + "[view]\nquantity = 3\n")
    assert main(["figure", "--session", str(tmp_path / "bad.toml"), "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        "isoforce figure: error: --session: session 'bad.toml': key 'view.quantity': needs a string, got 3"]
    assert not (tmp_path / "x.png").exists()
    assert main(["figure", "fivebar_singh", "--session", str(path), "--out", str(tmp_path / "x.png")]) == 2
    assert main(["figure", "--out", str(tmp_path / "x.png")]) == 2
    assert "DEVICE is required" in capsys.readouterr().err


def _colour_bar(fig):
    """The colour bar's axes of a map figure: the one whose label names the colours' range."""
    return next(ax for ax in fig.axes if "colours:" in ax.get_ylabel())


def test_figure_session_colours_a_box_plane_over_the_sessions_range(tmp_path, monkeypatch):
    """A session of the Falcon's 3D box map coloured over the whole volume draws its plane so:
    the exporter gets the volume (not the plane alone) and ``colour_range="volume"``, and the
    bar is labelled so and spans at least the plane's own values."""
    import app.cli.figure as figure
    import app.render.views as views
    calls, figures = [], []
    export, save = figure.export_view, views._save_matplotlib

    def spy_export(what, path, **kwargs):
        calls.append(kwargs)
        return export(what, path, **kwargs)

    def spy_save(fig, path, size, column=None):
        figures.append(fig)
        return save(fig, path, size, column)

    monkeypatch.setattr(figure, "export_view", spy_export)
    monkeypatch.setattr(views, "_save_matplotlib", spy_save)
    falcon = load_preset("novint_falcon")
    limits = {}
    for colours in ("plane", "volume"):
        path = write_session(tmp_path / f"{colours}.toml", Session(preset=falcon, mechanism=falcon.mechanism,
                                                                   plane=("z", 0.078), colour_range=colours))
        assert main(["figure", "--session", str(path), "--resolution", "12",
                     "--out", str(tmp_path / f"{colours}.png")]) == 0
        assert calls[-1]["colour_range"] == colours
        assert len(calls[-1]["workspace_map"].grid.axes) == (3 if colours == "volume" else 2)
        bar = _colour_bar(figures[-1])
        assert bar.get_ylabel().endswith("colours: " + ("whole volume" if colours == "volume" else "this plane"))
        limits[colours] = bar.get_ylim()
    # The lower limit is the minimum of the values coloured (``colour_limits``; only the upper
    # one is capped), and the plane is one of the volume's grid planes (both snap z to 73.6 mm),
    # so the volume's minimum is at most the plane's. The Falcon's box reaches far weaker points
    # off this plane, so the two bars differ.
    assert limits["volume"][0] <= limits["plane"][0] and limits["volume"] != limits["plane"]


def test_a_fitted_map_range_round_trips_and_figure_draws_over_it(tmp_path, monkeypatch):
    """View > Fit map to workspace's range is kept in ``[view.map]`` (only when it is not the
    preset's own), read back, and ``isoforce figure --session`` computes its map over it."""
    import tomllib

    import app.cli.figure as figure
    from app.logic.map_range import fit_grid
    inverse3 = load_preset("inverse3_prototype")
    mech = inverse3.mechanism.replace_display(proximal_length=250.0)
    fitted = fit_grid(mech, inverse3.grid)
    assert fitted != inverse3.grid
    plain = write_session(tmp_path / "plain.toml", Session(preset=inverse3, mechanism=mech))
    assert "map" not in tomllib.loads(plain.read_text())["view"]
    assert read_session(plain).preset.grid == inverse3.grid

    session = Session(preset=inverse3.replace(grid=fitted), mechanism=mech)
    path = write_session(tmp_path / "fitted.toml", session)
    table = tomllib.loads(path.read_text())["view"]["map"]
    assert table["axes"] == list(fitted.axes) and table["resolution"] == list(fitted.resolution)
    assert np.allclose(table["lower"], np.array(fitted.lower) * 1e3, rtol=1e-15)
    back = read_session(path)
    grid = back.preset.grid
    assert (grid.axes, grid.resolution, grid.fixed) == (fitted.axes, fitted.resolution, fitted.fixed)
    # m -> mm -> m: two roundings, each within eps/2 relative, so within eps together (2 eps bounds it).
    eps = np.finfo(float).eps
    assert np.allclose(grid.lower, fitted.lower, rtol=2 * eps, atol=0)
    assert np.allclose(grid.upper, fitted.upper, rtol=2 * eps, atol=0)
    assert session_to_toml(back) == session_to_toml(session)

    grids = []
    export = figure.export_view

    def spy(what, out, **kwargs):
        grids.append(kwargs["workspace_map"].grid)
        return export(what, out, **kwargs)

    monkeypatch.setattr(figure, "export_view", spy)
    assert main(["figure", "--session", str(path), "--resolution", "30", "--out", str(tmp_path / "m.png")]) == 0
    drawn = grids[-1]
    assert (drawn.axes, drawn.lower, drawn.upper) == (grid.axes, grid.lower, grid.upper)
