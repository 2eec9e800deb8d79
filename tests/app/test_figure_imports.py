"""``isoforce figure`` for a 3D view loads only what it draws with, and its edge fill matches scipy's.

The pose and workspace figures need numpy, pyvista (VTK) and matplotlib; a fresh
interpreter running one must not import scipy (0.3 s of CPU for ``scipy.ndimage``), Qt or
the subcommands it does not run, and a pose figure, which computes no map, not numba (its
import and its first kernel's load from the cache: 0.5 s of CPU, a third of the figure's)
nor the map's modules (``metrics.workspace`` and what it loads: 0.03-0.1 s).
Nothing here measures time: the modules a run loaded are what is checked.
"""
from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.scenes.slice_mesh import _edge_filled

ROOT = Path(__file__).resolve().parents[2]
#: The compiled kernels' compiler: its import and first kernel load cost a figure 0.5 s of CPU.
NUMBA = {"numba", "llvmlite"}
#: The map's modules and its statistics': a pose figure computes no map.
MAP_MODULES = {"metrics.workspace", "metrics.map_chunks", "metrics.statistics"}
NO_DISPLAY = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}

RUN = r"""
import json, sys
from app.cli import main
status = main(sys.argv[2:])
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""


def loaded_by(argv: list[str], tmp_path: Path, script: str = RUN) -> tuple[int, set[str], str]:
    """The exit status, the modules a fresh interpreter holds after ``isoforce *argv``, and its stderr."""
    result = subprocess.run([sys.executable, "-c", script, str(tmp_path), *argv], cwd=ROOT, env=NO_DISPLAY,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    return report["status"], set(report["modules"]), result.stderr


def tops(modules: set[str]) -> set[str]:
    return {m.split(".")[0] for m in modules}


def heavy_scipy(modules: set[str]) -> set[str]:
    """scipy modules beyond what numba itself loads.

    The compiled map kernels (``metrics.kernels``) run on numba, which imports the scipy package
    to check its version and, once it compiles or loads a kernel, scipy's BLAS wrappers
    (``numba.np.linalg.ensure_blas``); a subpackage beyond those (``scipy.ndimage``: 0.3 s of
    CPU) is what a figure must not pay for.
    """
    script = ("import sys, numba.np.linalg as nl; nl.ensure_blas(); "
              "print(' '.join(m for m in sys.modules if m.split('.')[0] == 'scipy'))")
    numba_own = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                               check=True).stdout.split()
    return {m for m in modules if m.split(".")[0] == "scipy"} - set(numba_own)


@pytest.mark.parametrize("view, device, resolution", [
    ("pose", "inverse3_prototype", 61), ("workspace", "inverse3_prototype", 61), ("workspace", "fivebar_singh", 61),
    ("workspace", "novint_falcon", 21)])        # a revolved slice, a flat slice, a box's volume
def test_a_3d_figure_imports_no_scipy_qt_or_other_subcommand(tmp_path, view, device, resolution):
    out = tmp_path / f"{view}.png"
    status, modules, stderr = loaded_by(["figure", device, "--view", view, "--resolution", str(resolution),
                                         "--size", "400x300", "--out", str(out)], tmp_path)
    assert status == 0 and out.stat().st_size > 0
    assert stderr == ""                                     # silent: "wrote" is on stdout
    unwanted = (tops(modules) & {"PySide6", "shiboken6", "pyvistaqt"}) | heavy_scipy(modules)
    if view == "pose":
        unwanted |= tops(modules) & NUMBA       # the pose's own linear algebra is numpy's: no map, no kernel
        unwanted |= modules & MAP_MODULES       # nor the map's modules (a tenth of a second of imports)
    else:
        assert tops(modules) & NUMBA == NUMBA   # a map runs on the compiled kernels: the check sees numba
    assert not unwanted, sorted(unwanted)
    # The shared helpers (arguments, usage error, formats, --plane, --max-time's progress, the process's start-up)
    # and pose, not another subcommand.
    shared = {"app.cli.figure", "app.cli._args", "app.cli._usage", "app.cli._format", "app.cli._plane",
              "app.cli._progress", "app.cli._process", "app.cli.pose"}
    others = {m for m in modules if m.startswith("app.cli.")} - shared
    assert not others, sorted(others)
    # Nor the other 3D view's scene modules, nor the session file format (no --session given).
    other_view = {"pose": {"app.scenes.workspace", "app.scenes.iso_labels", "app.scenes.volume_axes",
                           "app.scenes.slice_mesh", "app.scenes.classes"},
                  "workspace": {"app.scenes.pose", "app.scenes.pose_legend", "app.cli.pose"}}[view]
    assert not modules & (other_view | {"app.files.session"}), sorted(modules & (other_view | {"app.files.session"}))


def test_the_import_check_can_fail(tmp_path):
    """The same checks see scipy, numba and a scene module of the other view when a run imports them
    (here the script does, before the command)."""
    script = RUN.replace("import json, sys", "import json, sys, scipy.ndimage, numba, app.scenes.workspace, "
                                             "metrics.workspace")
    out = tmp_path / "pose.png"
    _, modules, _ = loaded_by(["figure", "fivebar_singh", "--view", "pose", "--size", "400x300", "--out", str(out)],
                              tmp_path, script)
    assert "scipy.ndimage" in heavy_scipy(modules)
    assert tops(modules) & NUMBA == NUMBA
    assert "app.scenes.workspace" in modules
    assert modules >= MAP_MODULES


def nearest_filled(values: np.ndarray) -> np.ndarray:
    """The reference: each non-finite entry of ``values`` given its nearest finite one's (scipy)."""
    from scipy import ndimage

    ok = np.isfinite(values)
    if not ok.any() or ok.all():
        return values
    return values[tuple(ndimage.distance_transform_edt(~ok, return_distances=False, return_indices=True))]


def random_masks(count: int, ndim: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    for k in range(count):
        shape = tuple(int(n) for n in rng.integers(2, 40 if ndim == 2 else 14, size=ndim))
        ok = rng.random(shape) < rng.uniform(0.02, 0.95)
        if k % 3 == 0:      # a workspace-like blob: one connected region with a ragged edge
            centre = np.array(shape) * rng.uniform(0.2, 0.8, size=ndim)
            r2 = sum((g - c) ** 2 for g, c in zip(np.indices(shape), centre))
            ok = r2 < (rng.uniform(0.2, 0.6) * max(shape)) ** 2
        yield ok, rng.normal(size=shape)


@pytest.mark.parametrize("ndim", [2, 3])
def test_edge_fill_is_scipys_nearest_fill_next_to_the_workspace(ndim):
    """Every non-finite sample with a finite one among its 3**ndim - 1 neighbours gets scipy's
    nearest value (ties included); the rest, which no clipped cell reaches, are nan."""
    checked = 0
    for ok, values in random_masks(300, ndim):
        values = np.where(ok, values, np.where(np.arange(ok.size).reshape(ok.shape) % 2, np.nan, np.inf))
        edge = _edge_filled(values)
        exact = nearest_filled(values)
        padded = np.pad(ok, 1)
        near = np.zeros_like(ok)
        for offset in itertools.product((-1, 0, 1), repeat=ndim):
            near |= padded[tuple(slice(1 + k, 1 + k + n) for k, n in zip(offset, ok.shape))]
        seen = near if ok.any() else np.ones_like(ok)
        np.testing.assert_array_equal(edge[seen], exact[seen])
        assert np.all(np.isnan(edge[~seen]))
        checked += np.count_nonzero(seen & ~ok)
    assert checked > 10_000


def test_edge_fill_refuses_other_shapes():
    with pytest.raises(ValueError, match="values: 2 or 3 axes"):
        _edge_filled(np.array([1.0, np.nan]))


def test_a_command_registers_only_itself_and_help_or_a_typo_every_command(capsys, monkeypatch):
    import app.cli as cli
    imported = []
    real = cli.importlib.import_module

    def recording(name, *args):
        if name.startswith("app.cli."):          # (import_module is the one module-wide function)
            imported.append(name)
        return real(name, *args)

    monkeypatch.setattr(cli.importlib, "import_module", recording)
    assert cli.main(["devices"]) == 0
    assert imported == ["app.cli.devices"]
    imported.clear()
    assert cli.main(["figurex"]) == 2
    err = capsys.readouterr().err
    assert imported == [f"app.cli.{c}" for c in cli.COMMANDS]
    assert "invalid choice: 'figurex'" in err and all(f"'{c}'" in err for c in cli.COMMANDS)
    imported.clear()
    assert cli.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert imported == [f"app.cli.{c}" for c in cli.COMMANDS] and all(c in out for c in cli.COMMANDS)
