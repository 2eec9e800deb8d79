"""Writing maps, statistics and figures to disk, atomically.

Every writer goes through ``atomic_write``: the data goes to a temporary file in the target's
folder, which replaces the target only once it is complete. A failed or interrupted export
therefore never leaves a half-written file, and never damages an older file of that name.

Units on disk follow the person-facing convention: coordinates in mm, forces in N; every file
names its units (a map CSV in its ``#`` comment lines, a statistics CSV in its ``unit`` column).
Numbers are written with the digits they have: the shortest decimal that reads back as the same
float64. A map CSV has a row per feasible point only (an infeasible point has no row) and spells
``inf`` (singular point) and ``nan`` (not defined there); JSON follows
``app.logic.json_values.json_safe`` (``null`` and ``"inf"``).
"""
from __future__ import annotations

import contextlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator

import numpy as np

# The quantities' table is imported by the map writers that read it: ``check_output``, the
# suffixes and ``atomic_write`` serve every command, most of which write no map (0.15 s of CPU
# for the quantity graph and the models' registry when imported here).
if TYPE_CHECKING:
    from metrics.workspace import WorkspaceMap

#: File types each export accepts, by suffix.
MAP_SUFFIXES = (".csv", ".npz")
STATS_SUFFIXES = (".json", ".csv")
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")

# The process umask, read once (reading it means setting it), so that a finished export gets
# the permissions a plain open() would have given it rather than mkstemp's private 0600.
_UMASK = os.umask(0o022)
os.umask(_UMASK)


def check_suffix(path: str | os.PathLike, suffixes: tuple[str, ...], name: str = "path") -> Path:
    """``path`` as a Path if it ends in one of ``suffixes`` (case-insensitive), else raise.

    The ValueError names the argument ``name`` and the value, e.g.
    ``"--out must end in .png, .svg or .pdf, got 'map.jpg'"``.
    """
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        listed = ", ".join(suffixes[:-1]) + f" or {suffixes[-1]}" if len(suffixes) > 1 else suffixes[0]
        raise ValueError(f"{name} must end in {listed}, got {str(path)!r}")
    return p


def check_output(path: str | os.PathLike, suffixes: tuple[str, ...], name: str = "--out") -> Path:
    """Check an output path before any computing: known suffix, names a file (not a folder), its
    folder exists and can be written (a temporary file is created there and removed: the only
    test that also holds for root and for read-only file systems).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``name``, the value and what is wrong.
    """
    target = check_suffix(path, suffixes, name)
    folder = target.parent
    if target.name in ("", ".", "..") or target.is_dir():
        raise ValueError(f"{name} is a folder, not a file: {str(path)!r}")
    if not folder.is_dir():
        raise ValueError(f"{name}: folder {str(folder)!r} does not exist, got {str(path)!r}")
    tmp = _new_temporary(target)
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        _TEMPORARIES.discard(tmp)
        raise ValueError(f"{name}: cannot write in folder {str(folder)!r} ({exc.strerror or exc}), "
                         f"got {str(path)!r}") from None
    os.close(fd)
    tmp.unlink(missing_ok=True)
    _TEMPORARIES.discard(tmp)
    return target


#: Temporary files of exports in progress, registered before they are created, so that an
#: interrupted command line (``remove_temporaries``) leaves none behind whatever the moment.
_TEMPORARIES: set[Path] = set()


def _new_temporary(target: Path) -> Path:
    """A fresh hidden name next to ``target`` (``.<stem>-XXXXXXXX<suffix>``), registered first."""
    import secrets

    while True:
        tmp = target.parent / f".{target.stem}-{secrets.token_hex(4)}{target.suffix}"
        if not os.path.lexists(tmp):
            _TEMPORARIES.add(tmp)
            return tmp


def remove_temporaries() -> None:
    """Delete every temporary file of an export still in progress (after an interrupt)."""
    for tmp in list(_TEMPORARIES):
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        _TEMPORARIES.discard(tmp)


@contextlib.contextmanager
def staged(targets: Iterable[Path]) -> Iterator[dict[Path, Path]]:
    """Several files written all or none (``isoforce figure`` with several views).

    Yields ``{target: temporary path}``: each temporary is a hidden name beside its target
    (same suffix), registered like ``atomic_write``'s so an interrupt removes it. When the block
    ends without an error every temporary is renamed onto its target; when it raises (or is
    interrupted) every temporary is removed and no target is touched.
    """
    stages = {Path(t): _new_temporary(Path(t)) for t in targets}
    try:
        yield stages
    except BaseException:
        for tmp in stages.values():
            tmp.unlink(missing_ok=True)
            _TEMPORARIES.discard(tmp)
        raise
    for target, tmp in stages.items():
        os.replace(tmp, target)
        _TEMPORARIES.discard(tmp)


def atomic_write(path: str | os.PathLike, write_fn: Callable[[Path], Any], *, name: str = "path") -> Path:
    """Create ``path`` by calling ``write_fn(tmp)`` on a temporary path, then renaming it.

    Parameters
    ----------
    path : str or PathLike
        The file to create or replace. Its folder must exist.
    write_fn : callable
        Called with the temporary file's path (same folder, same suffix, so writers that
        pick a format from the suffix still work); it must write the whole file there.
    name : str
        The argument name used in error messages (``"--out"`` from the command line).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        If the folder does not exist or cannot be written, naming ``name`` and the value.
        Whatever ``write_fn`` raises is re-raised unchanged, after the temporary file is
        removed; ``path`` is then untouched.
    """
    target = Path(path)
    folder = target.parent
    if target.name in ("", ".", ".."):
        raise ValueError(f"{name} must name a file, got {str(path)!r}")
    if not folder.is_dir():
        raise ValueError(f"{name}: folder {str(folder)!r} does not exist, got {str(path)!r}")
    if target.is_dir():
        raise ValueError(f"{name} is a folder, not a file: {str(path)!r}")
    # The name is registered before the file exists, so an interrupt at any moment (SIGTERM
    # between creating the file and entering the try below) still finds it: remove_temporaries.
    tmp = _new_temporary(target)
    try:
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError as exc:
            raise ValueError(f"{name}: cannot write in folder {str(folder)!r} ({exc.strerror or exc})") from None
        os.close(fd)
        write_fn(tmp)
        if not tmp.is_file():
            raise RuntimeError(f"write_fn did not leave a file at {tmp}")
        _flush_to_disk(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, target)
    except BaseException:
        # Any failure, including KeyboardInterrupt and SIGTERM (app.cli raises on it), leaves no
        # partial file behind.
        tmp.unlink(missing_ok=True)
        raise
    finally:
        _TEMPORARIES.discard(tmp)
    return target


def _flush_to_disk(path: Path) -> None:
    """fsync the finished temporary file so a crash after the rename cannot leave it empty."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_text(path: str | os.PathLike, text: str, *, name: str) -> Path:
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8", newline=""), name=name)


# -- maps -----------------------------------------------------------------------------------
def grid_coordinates_mm(grid) -> list[np.ndarray]:
    """Each axis's coordinates in mm as the grid defines them: ``numpy.linspace(lower, upper, n)``
    over the ends in mm.

    The ends are the grid's (SI) ends times 1e3 to 15 significant digits: a float64 holds at
    least 15 exact decimal digits, so this drops only the last-bit noise of the m -> mm product
    and keeps the decimal a preset was written in (a 10 mm grid reads ``-250.0``, not
    ``-250.00000000000003``). The result differs from ``grid.coordinates()[k] * 1e3`` by a few
    ulp at most.

    Parameters
    ----------
    grid : GridSpec
        The map's grid.

    Returns
    -------
    list of ndarray, shape (resolution[k],)
        mm, one per axis.
    """
    return [np.linspace(_mm(lo), _mm(hi), n) for lo, hi, n in zip(grid.lower, grid.upper, grid.resolution)]


def _mm(metres: float) -> float:
    return float(f"{metres * 1e3:.15g}")


#: Task coordinates that are angles (``kinematics`` names orientation coordinates so); a map's
#: grid carries no units, and its axes are positions in every preset.
_ANGLES = ("rx", "ry", "rz")


def _fixed_display(coordinate: str, value: float) -> tuple[float, str]:
    """A fixed task coordinate in display units: degrees for an angle, else mm."""
    if coordinate in _ANGLES:
        return float(f"{np.degrees(value):.15g}"), "deg"
    return _mm(value), "mm"


def map_columns(wmap: WorkspaceMap) -> tuple[list[str], list[np.ndarray]]:
    """Column names and columns of a map's CSV rows: the feasible points only.

    The columns are each axis's coordinate in mm (``grid_coordinates_mm``), then each per-point
    scalar quantity (vector nodes such as ``jacobian`` are skipped), at the feasible grid points
    in C order (``indexing="ij"``: the last axis fastest). Infeasible points have no row.

    Parameters
    ----------
    wmap : WorkspaceMap
        A kept map (``compute_map(..., keep=True)``).

    Returns
    -------
    names : list of str
        ``<axis>_mm`` per axis, then the quantities' names.
    columns : list of ndarray, shape (feasible_points,)
        float64 coordinates, and each quantity in its own dtype.
    """
    names = [f"{axis}_mm" for axis in wmap.grid.axes]
    grid_shape = tuple(wmap.grid.resolution)
    feasible = wmap.feasible.ravel()
    grids = np.meshgrid(*grid_coordinates_mm(wmap.grid), indexing="ij")
    columns: list[np.ndarray] = [g.ravel()[feasible] for g in grids]
    for quantity, values in wmap.values.items():
        if values.shape == grid_shape:
            names.append(quantity)
            columns.append(values.ravel()[feasible])
    return names, columns


def format_cell(value: Any) -> str:
    """One CSV cell: integers as integers, floats round-trip exactly (repr), nan/inf spelled out."""
    if isinstance(value, (np.integer, int)):
        return str(int(value))
    return repr(float(value))   # 'nan', 'inf', '-inf' or the shortest exact decimal


def _column_strings(column: np.ndarray) -> list[str]:
    """A column as cells: ``repr`` of Python floats is the shortest string that reads back exactly."""
    return list(map(repr if column.dtype.kind == "f" else str, column.tolist()))


CSV_ROWS_PER_BLOCK = 100_000


def _unit_text(unit: str) -> str:
    return unit if unit else "1 (dimensionless)"


def _map_csv_comments(wmap: WorkspaceMap, names: list[str], device: str) -> list[str]:
    """The comment block of a map CSV (without the leading ``# ``); its last line is the grid as JSON."""
    from metrics.bottleneck import BOTTLENECK_TIE
    from metrics.quantities import QUANTITIES

    grid = wmap.grid
    n_axes = len(grid.axes)
    described = []
    for q in names[n_axes:]:
        info = QUANTITIES[q]
        if wmap.values[q].dtype.kind in "iub":
            codes = info.description
            if q == "bottleneck":
                codes += f" Code: the actuator's index from 0; {BOTTLENECK_TIE} = a tie between actuators."
            described.append(f"{q}: integer code ({codes})")
        else:
            described.append(f"{q}: {_unit_text(info.unit)} ({info.label})")
    total = int(np.prod(grid.resolution))
    ends = "; ".join(f"{a}_mm: {n} points from {_mm(lo)!r} to {_mm(hi)!r} mm"
                     for a, lo, hi, n in zip(grid.axes, grid.lower, grid.upper, grid.resolution))
    fixed = {k: _fixed_display(k, v) for k, v in grid.fixed}
    spec = {"axes": list(grid.axes), "unit": "mm", "lower": [_mm(v) for v in grid.lower],
            "upper": [_mm(v) for v in grid.upper], "resolution": [int(n) for n in grid.resolution],
            "fixed": {k: v for k, (v, _) in fixed.items()}, "fixed_units": {k: u for k, (_, u) in fixed.items()},
            "integer_columns": [q for q in names[n_axes:] if wmap.values[q].dtype.kind in "iub"],
            "rows": wmap.feasible_points, "points": total}
    fixed_text = ", ".join(f"{k} = {v!r} {u}" for k, (v, u) in fixed.items())
    lines = [
        f"isoforce workspace map{f' of {device}' if device else ''}: one row per feasible grid point "
        f"({wmap.feasible_points} of {total}), C order (the last axis fastest)",
        "a grid point without a row is infeasible: unreachable, outside the joint limits or the body constraint",
        f"grid: {ends}" + (f"; fixed {fixed_text}" if fixed_text else "")
        + "; each axis is numpy.linspace of its ends, in mm",
        "columns: " + ", ".join(f"{a}_mm: mm" for a in grid.axes) + "; " + "; ".join(described),
        "cells: the shortest decimal that reads back as the same float64; inf = unbounded (a singular point), "
        "nan = not defined at this point",
        f"forces: {wmap.loading.describe()}",
    ]
    # The reading hint counts the lines itself: the comments, this hint, the JSON line, the names.
    lines.insert(1, f"read with app.files.export.read_map_csv, pandas.read_csv(path, comment='#') or "
                    f"numpy.loadtxt(path, delimiter=',', skiprows={len(lines) + 3})")
    lines.append("grid = " + json.dumps(spec, allow_nan=False))
    return lines


def write_map_csv(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", name: str = "path") -> Path:
    """The map's feasible points as CSV rows: ``<axis>_mm`` columns, then each quantity.

    The file starts with ``#`` comment lines that name the device, the units of every
    column, the grid (ends, points per axis, fixed coordinates; the last comment line holds it
    as JSON after ``grid = ``), the loading, and what the cells mean: infeasible points have
    no row, ``inf`` is a singular (unbounded) point, ``nan`` a value not defined there. Floats
    are the shortest decimal that reads back to the same float64 (``repr``); coordinates are
    ``grid_coordinates_mm``. ``read_map_csv`` rebuilds the grid-shaped arrays.

    Parameters
    ----------
    wmap : WorkspaceMap
        A kept map.
    path : str or PathLike
        A ``.csv`` file.
    device : str
        The device's key, named in the first comment line.
    name : str
        The argument name for error messages.

    Returns
    -------
    Path
        ``path``.
    """
    target = check_suffix(path, (".csv",), name)
    header, columns = map_columns(wmap)
    comments = _map_csv_comments(wmap, header, device)
    rows = columns[0].shape[0]

    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write("".join(f"# {line}\n" for line in comments))
            fh.write(",".join(header) + "\n")
            # Blocks of rows, joined as strings: ~2x faster than csv.writer, bounded memory.
            for start in range(0, rows, CSV_ROWS_PER_BLOCK):
                block = [_column_strings(c[start:start + CSV_ROWS_PER_BLOCK]) for c in columns]
                fh.write("\n".join(map(",".join, zip(*block))) + "\n")

    return atomic_write(target, write, name=name)


@dataclass(frozen=True)
class MapTable:
    """A map read back from its CSV (``read_map_csv``): grid-shaped arrays.

    ``coordinates`` holds each axis's coordinates in mm, shape (resolution[k],);
    ``feasible`` (resolution) is True where the file has a row; ``values`` maps each quantity
    to an array of grid shape (float64 with ``nan``, or int64 with ``-1``, where there is no
    row); ``fixed`` the fixed coordinates in mm.
    """

    axes: tuple[str, ...]
    coordinates: list[np.ndarray]
    feasible: np.ndarray
    values: dict[str, np.ndarray]
    fixed: dict[str, float]


def read_map_csv(path: str | os.PathLike) -> MapTable:
    """Read a map CSV written by ``write_map_csv`` back into grid-shaped arrays.

    Parameters
    ----------
    path : str or PathLike
        The CSV file.

    Returns
    -------
    MapTable

    Raises
    ------
    ValueError
        If the file lacks the ``grid = `` comment line or a row lies off the grid, naming the file.
    """
    path = Path(path)
    lines = path.read_text(encoding="utf-8").splitlines()
    spec, names, skip = None, None, 0
    for skip, line in enumerate(lines, start=1):
        if line.startswith("# grid = "):
            spec = json.loads(line[len("# grid = "):])
        elif not line.startswith("#"):
            names = line.split(",")
            break
    if spec is None or names is None:
        raise ValueError(f"{path}: not an isoforce map CSV (no '# grid = ' comment line or no column names)")
    shape = tuple(spec["resolution"])
    coords = [np.linspace(lo, hi, n) for lo, hi, n in zip(spec["lower"], spec["upper"], shape)]
    n_axes = len(shape)
    cells = np.array([line.split(",") for line in lines[skip:]], dtype=str).reshape(-1, len(names))
    index = []
    for k, (axis, c) in enumerate(zip(spec["axes"], coords)):
        column = cells[:, k].astype(np.float64)
        # The nearest grid index; the coordinates were written exactly, so they must match it.
        i = np.clip(np.rint((column - c[0]) / (c[-1] - c[0]) * (len(c) - 1)).astype(np.int64), 0, len(c) - 1)
        if not np.array_equal(c[i], column):
            raise ValueError(f"{path}: column {axis}_mm holds values off the grid of the 'grid = ' line")
        index.append(i)
    flat = np.ravel_multi_index(index, shape)
    feasible = np.zeros(int(np.prod(shape)), bool)
    feasible[flat] = True
    values = {}
    for k, q in enumerate(names[n_axes:], start=n_axes):
        code = q in spec.get("integer_columns", ())
        full = np.full(feasible.size, -1 if code else np.nan, np.int64 if code else np.float64)
        full[flat] = cells[:, k].astype(full.dtype)
        values[q] = full.reshape(shape)
    return MapTable(tuple(spec["axes"]), coords, feasible.reshape(shape), values, dict(spec["fixed"]))

def write_map_npz(wmap: WorkspaceMap, path: str | os.PathLike, *, name: str = "path") -> Path:
    """The map as arrays of grid shape: ``<axis>_mm`` (1D coordinates), ``points_mm``,
    ``feasible``, each quantity, plus ``axes``, ``quantities`` and ``units`` as string arrays.

    Loads with ``numpy.load(path)`` (no pickle).
    """
    from metrics.quantities import QUANTITIES

    target = check_suffix(path, (".npz",), name)
    arrays: dict[str, np.ndarray] = {}
    for axis, coords in zip(wmap.grid.axes, wmap.grid.coordinates()):
        arrays[f"{axis}_mm"] = coords * 1e3
    arrays["points_mm"] = wmap.points * 1e3
    arrays["feasible"] = wmap.feasible
    names = [q for q in wmap.values]
    for quantity in names:
        arrays[quantity] = wmap.values[quantity]
    arrays["axes"] = np.array(wmap.grid.axes)
    arrays["quantities"] = np.array(names, dtype=str)
    arrays["units"] = np.array([QUANTITIES[q].unit for q in names], dtype=str)

    def write(tmp: Path) -> None:
        # A file object, not a path: np.savez would append ".npz" to a name without it.
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    return atomic_write(target, write, name=name)


def write_map(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", name: str = "path") -> Path:
    """``write_map_csv`` or ``write_map_npz`` by the suffix of ``path``."""
    suffix = check_suffix(path, MAP_SUFFIXES, name).suffix.lower()
    if suffix == ".csv":
        return write_map_csv(wmap, path, device=device, name=name)
    return write_map_npz(wmap, path, name=name)


