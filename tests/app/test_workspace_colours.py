"""The 3D workspace views colour by the map view's key (issue 11: "the on-screen and exported maps
must show the same data and colour scale"), and the exported workspace figure says what it shows.

Before, the 3D views spanned the raw data range: the Falcon's condition number from 1.51 to 3870
on a log scale, its four iso-surfaces (1.9 to 5.9) all in the bottom purple, where the map view
caps its colours at 176; the isotropic force from the grid's 0.0133 N near a singularity.
"""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET

import matplotlib
import numpy as np
import pytest

from app import scenes
from app.logic.colour_scale import category_classes, colour_scale
from app.logic.display_units import display_unit
from app.render.views import _workspace_scene, export_view
from metrics.quantities import CORE_QUANTITIES, QUANTITIES
from metrics.workspace import compute_map
from resources import list_presets, load_preset

CASES = [("novint_falcon", "condition_number", 21), ("novint_falcon", "isotropic_force", 21),
         ("inverse3_prototype", "isotropic_force", 81), ("fivebar_singh", "condition_number", 81),
         ("phantom_premium_15", "anisotropic_force", 81)]


def workspace_map(key: str, quantity: str, resolution: int):
    preset = load_preset(key)
    quantities = tuple(sorted(set(CORE_QUANTITIES) | {quantity}))
    return preset, compute_map(preset.mechanism, preset.grid.with_resolution(resolution), quantities)


@pytest.mark.parametrize("key, quantity, resolution", CASES)
def test_the_3d_scene_colours_by_the_map_views_scale(key, quantity, resolution):
    preset, wmap = workspace_map(key, quantity, resolution)
    # The map view's scale: the colour scale of the map's values in display units (map_view, map_picture).
    factor = display_unit(quantity)[1]
    want = colour_scale(quantity, preset, [(wmap.values[quantity] * factor, wmap.feasible)])
    plotter = _workspace_scene(preset.mechanism, wmap, quantity, size=(400, 300))
    try:
        name = "box_plane" if len(wmap.grid.axes) == 3 else "workspace"
        mapper = plotter.actors[name].mapper
        np.testing.assert_allclose(mapper.scalar_range, want.limits, rtol=1e-12)
        assert bool(mapper.lookup_table.log_scale) == want.log
        title = next(iter(plotter.scalar_bars.keys()))
        assert ("colours capped at" in title) == want.capped
        if want.capped:
            assert f"capped at {want.limits[1]:.3g}" in title
    finally:
        plotter.close()


def test_the_falcons_figure_labels_its_surfaces_and_states_its_whole_grid(tmp_path, monkeypatch):
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")     # SVG text as text
    preset, wmap = workspace_map("novint_falcon", "condition_number", 21)
    plotter = _workspace_scene(preset.mechanism, wmap, "condition_number", size=(400, 300))
    try:
        assert scenes.ISO_LABEL_ACTOR in plotter.actors                 # the surfaces carry their values
        levels = scenes.iso_levels(scenes.box_image(wmap, "condition_number").point_data["condition_number"],
                                   "condition_number")
    finally:
        plotter.close()
    out = export_view("workspace", tmp_path / "ws.svg", preset=preset, mechanism=preset.mechanism,
                      workspace_map=wmap, quantity="condition_number")
    text = " ".join(" ".join(el.itertext()) for el in ET.parse(out).iter() if el.tag.endswith("text"))
    assert f"{' x '.join(map(str, wmap.grid.resolution))} grid" in text           # 21 x 21 x 21, not 21 x 21
    assert "iso-surfaces of condition number at " + ", ".join(f"{v:.3g}" for v in levels) in text


def _inside_pixels(picture: np.ndarray) -> np.ndarray:
    """The pixels (k, 3) of ``picture`` (h, w, 3) with no background (white) pixel next to them:
    an edge pixel's multisamples blend the picture with the white."""
    white = np.all(picture >= 250, axis=2)
    padded = np.pad(white, 1, constant_values=True)
    near_white = np.zeros_like(white)
    for dy in range(3):
        for dx in range(3):
            near_white |= padded[dy: dy + white.shape[0], dx: dx + white.shape[1]]
    return picture[~near_white]


def _distance_to_key(pixels: np.ndarray, key: np.ndarray) -> np.ndarray:
    """For each pixel (k, 3), the distance (0-255 units) to the nearest key colour (c, 3)."""
    return np.min(np.linalg.norm(pixels[:, None, :] - key[None], axis=2), axis=1)


@pytest.mark.parametrize("key", ["phantom_premium_15", "fivebar_singh"])
def test_a_flat_workspace_is_seen_square_on_in_the_keys_own_colours(key):
    """A flat picture (a planar map, the PHANToM's y = 0 slice) is unlit and seen square on: every
    pixel inside it is a colour of the bar's key. (The PHANToM's slice was clipped to nothing, a
    traceback; lit obliquely, the key's yellow showed as olive, 60 units away.)"""
    from app.scenes.snapshot import colour_bar_of, scene_figure
    preset, wmap = workspace_map(key, "isotropic_force", 81)
    plotter = _workspace_scene(preset.mechanism, wmap, "isotropic_force", size=(500, 400))
    try:
        assert scenes.flat_axes(preset.mechanism, wmap.grid) == ("xz" if key.startswith("phantom") else "xy")
        lut = plotter.actors["workspace"].mapper.lookup_table
        key_colours = np.asarray(lut.values, float)[:, :3]
        colour_bar_of(plotter)                    # the figure's bar is matplotlib's: VTK's is taken out
        picture = scene_figure(plotter, (500, 400)).image.astype(float)
    finally:
        plotter.close()
    inside = _inside_pixels(picture)
    assert len(inside) > 0.2 * picture.shape[0] * picture.shape[1]
    # 8-bit colours round each channel by half a unit or less (sqrt(3)/2 in all), and a pixel's
    # multisamples may blend two neighbouring cells, up to half the largest step between key colours.
    step = np.max(np.linalg.norm(np.diff(key_colours, axis=0), axis=1))
    sample = inside[np.random.default_rng(0).choice(len(inside), size=min(4000, len(inside)), replace=False)]
    assert _distance_to_key(sample, key_colours).max() <= np.sqrt(3) / 2 + step / 2 + 1e-9


def test_the_revolved_figures_flat_faces_are_the_maps_slice_in_the_keys_own_colours():
    """The Inverse3's figure: the cut y = 0 and the ends of the base joint's range are slices of
    the map, drawn unlit, so each of their pixels is a key colour; the shell round them is lit.
    (Lit, the end face read near black: 50 to 68 units from every key colour.)"""
    from app.scenes.snapshot import scene_figure
    preset, wmap = workspace_map("inverse3_prototype", "isotropic_force", 81)
    plotter = _workspace_scene(preset.mechanism, wmap, "isotropic_force", size=(500, 400))
    try:
        flat, shell = plotter.actors[scenes.CUT_FACE_ACTOR], plotter.actors["workspace"]
        assert not flat.prop.lighting and shell.prop.lighting
        # Every flat cell on one of the three planes; none of the shell's.
        planes = scenes.workspace._revolved_planes(preset.mechanism, wmap.grid)
        size = np.ptp(np.asarray(shell.mapper.dataset.points), axis=0).max()
        for actor, on in ((flat, True), (shell, False)):
            centres = np.asarray(actor._isoforce_dataset.cell_centers().points
                                 if hasattr(actor, "_isoforce_dataset") else actor.mapper.dataset.cell_centers().points)
            near = np.min([np.abs(centres @ n - c) for n, c in planes], axis=0) <= 1e-6 * size
            assert near.all() if on else not near.any()
        key_colours = np.asarray(flat.mapper.lookup_table.values, float)[:, :3]
        plotter.remove_actor("workspace")                # the flat faces alone, no bar and its text
        while plotter.scalar_bars:
            plotter.remove_scalar_bar()
        picture = scene_figure(plotter, (500, 400)).image.astype(float)
    finally:
        plotter.close()
    inside = _inside_pixels(picture)
    assert len(inside) > 0.05 * picture.shape[0] * picture.shape[1]
    step = np.max(np.linalg.norm(np.diff(key_colours, axis=0), axis=1))      # as for the flat pictures
    sample = inside[np.random.default_rng(0).choice(len(inside), size=min(4000, len(inside)), replace=False)]
    distance = _distance_to_key(sample, key_colours)
    # As for a flat picture, but for the pixels on a seam where a face's edge passes over another
    # face (their multisamples blend two faces, not two neighbouring cells): a few in a thousand.
    assert np.mean(distance <= np.sqrt(3) / 2 + step / 2 + 1e-9) >= 0.995, np.sort(distance)[-20:]
    # Lit, the end face was 50 to 68 units off every key colour.
    assert distance.max() < 20


@pytest.mark.parametrize("key", list_presets())
def test_every_presets_workspace_figure_renders_its_map(key, tmp_path):
    """Every shipped preset's workspace view renders (the PHANToM family's raised a KeyError)."""
    preset = load_preset(key)
    quantities = tuple(sorted(set(CORE_QUANTITIES) | {"isotropic_force"}))
    wmap = compute_map(preset.mechanism, preset.grid.with_resolution(21), quantities)
    plotter = _workspace_scene(preset.mechanism, wmap, "isotropic_force", size=(300, 240))
    try:
        name = "box_plane" if len(wmap.grid.axes) == 3 else "workspace"
        assert plotter.actors[name].mapper.dataset.n_cells > 0           # the map is drawn, not an empty scene
    finally:
        plotter.close()
    out = export_view("workspace", tmp_path / "ws.png", preset=preset, mechanism=preset.mechanism,
                      workspace_map=wmap, quantity="isotropic_force", size=(300, 240))
    assert matplotlib.image.imread(out).shape[0] > 0


def test_iso_labels_in_micrometres_and_none_on_a_maps_own_surface():
    """Labels carry non-ASCII units (pyvista's string conversion refused "µm": the Falcon's
    spatial-resolution workspace was a traceback), and a map's surface with few distinct values
    (classes, a coarse grid) gets none: its values are samples, not iso-surface levels."""
    preset, wmap = workspace_map("novint_falcon", "spatial_resolution", 21)
    plotter = _workspace_scene(preset.mechanism, wmap, "spatial_resolution", size=(400, 300))
    try:
        labels = plotter.actors[scenes.ISO_LABEL_ACTOR].GetMapper().GetInputAlgorithm().GetInput()
        texts = labels.GetPointData().GetAbstractArray("iso_label")
        assert [texts.GetValue(i) for i in range(texts.GetNumberOfValues())][0].endswith(" µm")
    finally:
        plotter.close()
    for key, quantity, resolution in (("fivebar_singh", "bottleneck", 41), ("fivebar_singh", "isotropic_force", 4)):
        preset, wmap = workspace_map(key, quantity, resolution)
        plotter = _workspace_scene(preset.mechanism, wmap, quantity, size=(400, 300))
        try:
            assert scenes.ISO_LABEL_ACTOR not in plotter.actors, (quantity, resolution)
        finally:
            plotter.close()


# Categorical quantities: the map view's classes, colours and names (issue 11: the 3D views drew
# the class codes through matplotlib's tab10 over their range, a bar of numbers for a key: the
# five-bar's theta_2 cyan where the map shows it orange, and lines of red, green and pink along
# the class boundaries, colours of no class, where point data interpolated the codes).
CLASS_CASES = [("fivebar_singh", "bottleneck"), ("phantom_premium_15", "bottleneck"),
               ("fivebar_singh", "singularity")]


def map_classes(preset, wmap, quantity: str):
    """The map view's classes of ``wmap``: their names, their colours as the map draws them (RGB
    bytes, (k, 3)) and each point's class index (masked where it has none), from
    ``colour_scale`` as ``map_view`` and ``map_picture`` make it (with the preset)."""
    scale = colour_scale(quantity, preset, [(wmap.values[quantity], wmap.feasible)])
    names = tuple(name for _, name, _ in category_classes(quantity, preset, wmap.values[quantity][wmap.feasible]))
    rgb = scale.lut_bytes[: len(names), :3].astype(float)
    return names, rgb, scale.to_data(wmap.values[quantity], wmap.feasible)


def key_names(lut) -> tuple[str, ...]:
    """The names a lookup table's annotations give its values, in the values' order."""
    pairs = sorted((lut.GetAnnotatedValue(i).ToFloat(), lut.GetAnnotation(i))
                   for i in range(lut.GetNumberOfAnnotatedValues()))
    return tuple(name for _, name in pairs)


def nearest_sample_class(points: np.ndarray, grid, index) -> np.ndarray:
    """The class index (masked array) of the map sample nearest each of ``points`` (k, 3), m."""
    at = []
    for axis, c in zip(grid.axes, grid.coordinates()):
        k = np.rint((points[:, "xyz".index(axis)] - c[0]) / (c[1] - c[0])).astype(int)
        at.append(np.clip(k, 0, len(c) - 1))
    return index[tuple(at)]


def _neighbour_shifts(grid, step) -> list[tuple[float, float, float]]:
    """Shifts (m, 3D) to a point's nearest sample's 3 x 3 neighbours in the map's plane."""
    shifts = []
    for a in (-1, 0, 1):
        for b in (-1, 0, 1):
            shift = [0.0, 0.0, 0.0]
            shift["xyz".index(grid.axes[0])] = a * step[0]
            shift["xyz".index(grid.axes[1])] = b * step[1]
            shifts.append(tuple(shift))
    return shifts


@pytest.mark.parametrize("key, quantity", CLASS_CASES + [("inverse3_prototype", "bottleneck"),
                                                         ("novint_falcon", "bottleneck")])
def test_classes_are_drawn_cell_by_cell_in_the_maps_colours_with_its_names(key, quantity):
    """Each drawn cell is one map sample's class (cell data: no colour interpolated between two
    classes), looked up in the map's own class colours byte for byte, and the key names them."""
    preset, wmap = workspace_map(key, quantity, 21 if key == "novint_falcon" else 81)
    names, rgb, index = map_classes(preset, wmap, quantity)
    plotter = _workspace_scene(preset.mechanism, wmap, quantity, size=(400, 300))
    try:
        name = "box_plane" if len(wmap.grid.axes) == 3 else "workspace"
        mapper = plotter.actors[name].mapper
        lut = mapper.lookup_table
        np.testing.assert_array_equal(np.asarray(lut.values, float)[:, :3], rgb)
        assert lut.GetIndexedLookup()                 # an index that is no class is no colour of the table
        assert key_names(lut) == names
        bar = plotter.scalar_bars[QUANTITIES[quantity].label]
        assert bar.GetLookupTable() is lut and not bar.GetDrawTickLabels()    # names, no numbers
        assert mapper.GetScalarModeAsString() == "UseCellData"
        drawn = np.asarray(mapper.dataset.cell_data[quantity], float)
        shown = drawn[np.isfinite(drawn)]
        assert shown.size and set(np.unique(shown)) <= set(range(len(names)))
        if not scenes.is_revolved(preset.mechanism, wmap.grid):
            # Nearest-sample colouring, as the map view's cells: each whole cell centred on its
            # sample and of its class; a cell cut by the smooth edge of the workspace is of the
            # class of a sample next to its centre's nearest (that one may be outside).
            mesh = mapper.dataset
            centres = np.asarray(mesh.cell_centers().points, float)
            want = nearest_sample_class(centres, wmap.grid, index)
            step = [c[1] - c[0] for c in wmap.grid.coordinates()]
            area = np.asarray(mesh.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
            whole = np.isclose(area, step[0] * step[1], rtol=1e-9)
            assert whole.sum() > 0.8 * len(whole)
            np.testing.assert_array_equal(np.ma.filled(want[whole].astype(float), np.nan), drawn[whole])
            for centre, cls in zip(centres[~whole], drawn[~whole]):
                near = [nearest_sample_class((centre + np.array(shift))[None], wmap.grid, index)[0]
                        for shift in _neighbour_shifts(wmap.grid, step)]
                assert cls in [n for n in near if n is not np.ma.masked]
    finally:
        plotter.close()


def _uniform(picture: np.ndarray) -> np.ndarray:
    """Pixels (h - 2, w - 2) of ``picture`` (h, w, 3) whose 3 x 3 block is one colour (the border left out)."""
    h, w = picture.shape[:2]
    centre = picture[1:-1, 1:-1]
    same = np.ones((h - 2, w - 2), bool)
    for dy in range(3):
        for dx in range(3):
            same &= np.all(picture[dy: dy + h - 2, dx: dx + w - 2] == centre, axis=2)
    return same


@pytest.mark.parametrize("key, quantity", CLASS_CASES)
def test_a_flat_class_picture_shows_the_maps_class_colours_and_no_other(key, quantity):
    """Rendered, a flat class map's regions are the map's class colours: every pixel inside a
    region (its 3 x 3 block one colour: no multisample blend of a cell edge with the white or
    with the next class) is a class colour, and every class of 2 % of the points or more shows."""
    from app.scenes.snapshot import colour_bar_of, scene_figure
    preset, wmap = workspace_map(key, quantity, 81)
    names, rgb, index = map_classes(preset, wmap, quantity)
    plotter = _workspace_scene(preset.mechanism, wmap, quantity, size=(500, 400))
    try:
        colour_bar_of(plotter)                    # the figure's key is matplotlib's: VTK's is taken out
        picture = scene_figure(plotter, (500, 400)).image.astype(float)
    finally:
        plotter.close()
    same = _uniform(picture)
    inner = picture[1:-1, 1:-1][same & ~np.all(picture[1:-1, 1:-1] >= 250, axis=2)]
    assert len(inner) > 0.2 * same.size
    # 8-bit colours round each channel by half a unit or less: sqrt(3)/2 in all.
    distance = np.linalg.norm(inner[:, None, :] - rgb[None], axis=2)
    assert distance.min(axis=1).max() <= np.sqrt(3) / 2
    shown = set(np.unique(distance.argmin(axis=1)).tolist())
    counts = np.array([np.count_nonzero(index == i) for i in range(len(names))])
    assert set(np.flatnonzero(counts >= 0.02 * counts.sum()).tolist()) <= shown


@pytest.mark.parametrize("key", ["fivebar_singh", "novint_falcon"])
def test_the_workspace_figures_key_names_the_maps_classes(key, tmp_path, monkeypatch):
    """The exported workspace figure's key of a class map is a legend of the map's class names
    under the quantity's label (the bar of numbers is gone; a box map's classes had no key)."""
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")     # SVG text as text
    preset, wmap = workspace_map(key, "bottleneck", 21 if key == "novint_falcon" else 81)
    names, _, _ = map_classes(preset, wmap, "bottleneck")
    out = export_view("workspace", tmp_path / "ws.svg", preset=preset, mechanism=preset.mechanism,
                      workspace_map=wmap, quantity="bottleneck")
    texts = [" ".join(el.itertext()).strip() for el in ET.parse(out).iter() if el.tag.endswith("text")]
    assert QUANTITIES["bottleneck"].label in texts
    assert set(names) <= set(texts)
    assert not any(t.replace(".", "").replace("−", "").isdigit() for t in texts)      # no numbered ticks


def test_a_hole_or_a_crack_in_a_class_map_stays_open_in_the_3d_picture():
    """A sample inside the workspace without a class (infeasible: a hole; a line of them one
    sample wide: a crack) is blank in the map view, so in the 3D picture too, as a magnitude's
    picture leaves it; the samples around it keep their classes."""
    preset, wmap = workspace_map("fivebar_singh", "bottleneck", 41)
    feasible = wmap.feasible
    inner = feasible.copy()
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            inner &= np.roll(np.roll(feasible, di, 0), dj, 1)
    i, j = np.argwhere(inner)[len(np.argwhere(inner)) // 2]
    hole = feasible.copy()
    hole[i, j] = False
    crack = feasible.copy()
    crack[:, j] = False

    def covered(mask, samples) -> list[bool]:
        holed = dataclasses.replace(wmap, feasible=mask)
        xs, ys = holed.grid.coordinates()
        names = preset.mechanism.task_names
        out = {}
        for quantity in ("bottleneck", "condition_number"):
            volume = scenes.workspace_volume(holed, quantity, preset.mechanism)
            out[quantity] = []
            for a, b in samples:
                point = [0.0, 0.0, 0.0]
                point[names.index(holed.grid.axes[0])], point[names.index(holed.grid.axes[1])] = xs[a], ys[b]
                out[quantity].append(volume.find_containing_cell(point) >= 0)
        return out

    assert covered(hole, [(i, j)]) == {"bottleneck": [False], "condition_number": [False]}
    assert covered(hole, [(i + 1, j), (i, j + 1)])["bottleneck"] == [True, True]
    gap = [(a, j) for a in np.flatnonzero(feasible[:, j])]
    assert len(gap) > 5
    cracked = covered(crack, gap)
    assert not any(cracked["bottleneck"]) and not any(cracked["condition_number"])


def test_a_class_map_of_one_lone_sample_draws_nothing_instead_of_failing():
    """One classed sample with no classed neighbour: no cell corner reaches a share of one half,
    so the cut is empty. Before, reading the empty cut's cell centres raised KeyError."""
    preset, wmap = workspace_map("fivebar_singh", "bottleneck", 41)
    i, j = np.argwhere(wmap.feasible)[len(np.argwhere(wmap.feasible)) // 2]
    lone = np.zeros_like(wmap.feasible)
    lone[i, j] = True
    volume = scenes.workspace_volume(dataclasses.replace(wmap, feasible=lone), "bottleneck", preset.mechanism)
    assert volume.n_cells == 0
