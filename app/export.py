"""Writing maps, statistics and figures to disk, atomically.

Every writer goes through ``atomic_write``: the data goes to a temporary file in the target's
folder, which replaces the target only once it is complete. A failed or interrupted export
therefore never leaves a half-written file, and never damages an older file of that name.

Units on disk follow the person-facing convention: coordinates in mm, forces in N.
Non-finite values: CSV writes ``nan`` (infeasible point) and ``inf`` (singular point), which
``numpy.loadtxt`` and spreadsheet programs read back; JSON follows ``app.pose_report.json_safe``
(``null`` and ``"inf"``).
"""
from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import Any, Callable

import numpy as np

from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap, resolution_error

from .pose_report import json_safe

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


def _write_text(path: str | os.PathLike, text: str, *, name: str) -> Path:
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8", newline=""), name=name)


# -- maps -----------------------------------------------------------------------------------
def map_columns(wmap: WorkspaceMap) -> tuple[list[str], list[np.ndarray]]:
    """Column names and flat columns of a map: axis coordinates (mm), feasible, each quantity.

    Only per-point scalar quantities become columns (vector nodes such as ``jacobian`` are
    skipped). Rows run over the grid in C order (``indexing="ij"``: the last axis fastest).
    """
    names = [f"{axis}_mm" for axis in wmap.grid.axes]
    grid_shape = tuple(wmap.grid.resolution)
    # The same meshgrid GridSpec.points builds, so the coordinates are exactly the map's.
    grids = np.meshgrid(*wmap.grid.coordinates(), indexing="ij")
    columns: list[np.ndarray] = [g.ravel() * 1e3 for g in grids]
    names.append("feasible")
    columns.append(wmap.feasible.ravel().astype(np.int8))
    for quantity, values in wmap.values.items():
        if values.shape == grid_shape:
            names.append(quantity)
            columns.append(values.ravel())
    return names, columns


def _format_cell(value: Any) -> str:
    """One CSV cell: integers as integers, floats round-trip exactly (repr), nan/inf spelled out."""
    if isinstance(value, (np.integer, int)):
        return str(int(value))
    return repr(float(value))   # 'nan', 'inf', '-inf' or the shortest exact decimal


def _column_strings(column: np.ndarray) -> list[str]:
    """A column as cells: ``repr`` of Python floats is the shortest string that reads back exactly."""
    return list(map(repr if column.dtype.kind == "f" else str, column.tolist()))


CSV_ROWS_PER_BLOCK = 100_000


def write_map_csv(wmap: WorkspaceMap, path: str | os.PathLike, *, name: str = "path") -> Path:
    """One row per grid point: ``<axis>_mm`` columns, ``feasible`` (0/1), each quantity.

    Infeasible points hold ``nan`` (``-1`` for categorical quantities such as ``bottleneck``);
    singular ones ``inf``. Floats are written exactly (shortest round-trip decimal). Read
    back with ``numpy.loadtxt(path, delimiter=",", skiprows=1)``.
    """
    target = check_suffix(path, (".csv",), name)
    header, columns = map_columns(wmap)
    rows = columns[0].shape[0]

    def write(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(header) + "\n")
            # Blocks of rows, joined as strings: ~2x faster than csv.writer, bounded memory.
            for start in range(0, rows, CSV_ROWS_PER_BLOCK):
                block = [_column_strings(c[start:start + CSV_ROWS_PER_BLOCK]) for c in columns]
                fh.write("\n".join(map(",".join, zip(*block))) + "\n")

    return atomic_write(target, write, name=name)


def write_map_npz(wmap: WorkspaceMap, path: str | os.PathLike, *, name: str = "path") -> Path:
    """The map as arrays of grid shape: ``<axis>_mm`` (1D coordinates), ``points_mm``,
    ``feasible``, each quantity, plus ``axes``, ``quantities`` and ``units`` as string arrays.

    Loads with ``numpy.load(path)`` (no pickle).
    """
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


def write_map(wmap: WorkspaceMap, path: str | os.PathLike, *, name: str = "path") -> Path:
    """``write_map_csv`` or ``write_map_npz`` by the suffix of ``path``."""
    suffix = check_suffix(path, MAP_SUFFIXES, name).suffix.lower()
    return (write_map_csv if suffix == ".csv" else write_map_npz)(wmap, path, name=name)


# -- statistics -----------------------------------------------------------------------------
def stats_summary(wmap: WorkspaceMap, *, device: str = "", quantities=None) -> dict[str, Any]:
    """A map's global figures as a JSON-ready dict (the object ``isoforce stats --json`` prints).

    Keys: ``device``, ``resolution`` (points per axis), ``axes``, ``task_names`` (the
    coordinates of ``argmin``/``argmax``), ``feasible_points``, ``total_points``,
    ``seconds`` (compute time), ``quantities``: per quantity ``min``, ``max``, ``mean``,
    ``sd`` (ddof = 1), ``median``, ``p05``, ``p95``, ``count`` (regular points),
    ``argmin`` and ``argmax`` (task points in mm), ``singular_points`` (feasible points the
    mechanism calls singular, left out of every figure) with ``singular_at``, ``unbounded``
    (the supremum is infinite in truth: ``max`` is ``"inf"``) with ``unbounded_at``, ``unit``,
    and ``resolution_error``: the estimated error of each figure due to the grid
    (``metrics.workspace.resolution_error``: the change from half the resolution; ``null``
    for an unbounded maximum). Top level: ``singular_points``, and ``gci`` (the global
    conditioning index, mean of 1 / condition number, with its ``resolution_error``) when
    ``inverse_condition_number`` was computed.
    """
    names = list(wmap.stats) if quantities is None else list(quantities)
    errors = resolution_error(wmap)
    per_quantity = {}
    for q in names:
        entry = wmap.stats[q].as_dict(scale=1e3)
        entry["unit"] = QUANTITIES[q].unit
        entry["resolution_error"] = errors.get(q)
        per_quantity[q] = entry
    summary = {
        "device": device,
        "resolution": list(wmap.grid.resolution),
        "axes": list(wmap.grid.axes),
        "task_names": list(wmap.task_names),
        "feasible_points": wmap.feasible_points,
        "total_points": int(np.prod(wmap.grid.resolution)),
        "seconds": wmap.seconds,
        "singular_points": wmap.singular_points,
        "quantities": per_quantity,
    }
    if wmap.gci is not None:
        summary["gci"] = {"value": wmap.gci, "resolution_error": wmap.gci_error,
                          "definition": "mean of 1 / condition number over the feasible points "
                                        "(Gosselin and Angeles 1991); singular points count 0"}
    return json_safe(summary)


def dumps(obj: Any) -> str:
    """Strict JSON text of ``obj`` (after ``json_safe``): never ``NaN`` or ``Infinity``."""
    return json.dumps(json_safe(obj), indent=2, allow_nan=False)


def write_stats_json(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", quantities=None,
                     name: str = "path") -> Path:
    """``stats_summary`` as a JSON file."""
    check_suffix(path, (".json",), name)
    summary = stats_summary(wmap, device=device, quantities=quantities)
    return _write_text(path, dumps(summary) + "\n", name=name)


STATS_CSV_COLUMNS = ("quantity", "unit", "min", "max", "mean", "sd", "median", "p05", "p95", "count",
                     "singular_points", "unbounded")


def write_stats_csv(wmap: WorkspaceMap, path: str | os.PathLike, *, quantities=None, name: str = "path") -> Path:
    """One row per quantity: ``STATS_CSV_COLUMNS``, then ``argmin_<c>_mm`` and ``argmax_<c>_mm``.

    The argmin/argmax columns cover every task coordinate ``c`` (``x``, ``y``, ...), as the
    extremes are points in task space.
    """
    check_suffix(path, (".csv",), name)
    names = list(wmap.stats) if quantities is None else list(quantities)
    coords = list(wmap.task_names)
    m = len(coords)
    header = list(STATS_CSV_COLUMNS) + [f"argmin_{c}_mm" for c in coords] + [f"argmax_{c}_mm" for c in coords]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for q in names:
        s = wmap.stats[q]
        argmin = list(s.argmin) or [float("nan")] * m
        argmax = list(s.argmax) or [float("nan")] * m
        writer.writerow([q, QUANTITIES[q].unit]
                        + [_format_cell(v) for v in (s.min, s.max, s.mean, s.sd, s.median, s.p05, s.p95)]
                        + [str(s.count), str(s.singular_points), "true" if s.unbounded else "false"]
                        + [_format_cell(v * 1e3) for v in argmin + argmax])
    return _write_text(path, buffer.getvalue(), name=name)


def write_stats(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", quantities=None,
                name: str = "path") -> Path:
    """``write_stats_json`` or ``write_stats_csv`` by the suffix of ``path``."""
    suffix = check_suffix(path, STATS_SUFFIXES, name).suffix.lower()
    if suffix == ".json":
        return write_stats_json(wmap, path, device=device, quantities=quantities, name=name)
    return write_stats_csv(wmap, path, quantities=quantities, name=name)
