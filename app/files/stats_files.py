"""A map's statistics as files: JSON (``isoforce stats --json``'s summary) or CSV, one row per
quantity, every figure beside its resolution error; written atomically (``export.atomic_write``).
"""
from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from app.files.export import STATS_SUFFIXES, check_suffix, format_cell, write_text
from app.logic.json_values import dumps, json_safe  # noqa: F401  (dumps re-exported: the summary's text)
from metrics.quantities import QUANTITIES
from metrics.workspace import FIGURES, WorkspaceMap, resolution_error


# -- statistics -----------------------------------------------------------------------------
def stats_summary(wmap: WorkspaceMap, *, device: str = "", quantities=None) -> dict[str, Any]:
    """A map's global figures as a JSON-ready dict (the object ``isoforce stats --json`` prints).

    Keys: ``device``, ``resolution`` (points per axis), ``axes``, ``task_names`` (the
    coordinates of ``argmin``/``argmax``), ``feasible_points``, ``total_points``,
    ``seconds`` (compute time), ``quantities``: per quantity ``min``, ``max``, ``mean``,
    ``sd`` (ddof = 1), ``median``, ``p05``, ``p95``, ``count`` (regular points),
    ``argmin`` and ``argmax`` (task points in mm), ``singular_points`` (feasible points the
    mechanism calls singular, left out of the mean, SD and quantiles) with ``singular_at``, ``unbounded``
    (the supremum is infinite in truth: ``max`` is ``"inf"``) with ``unbounded_at``, ``unit``,
    and ``resolution_error``: the estimated error of each figure due to the grid
    (``metrics.workspace.resolution_error``: the change from half the resolution; ``null``
    for an unbounded maximum) and ``resolution_error_order``: the observed order p of that
    error, error ~ h^p (``metrics.workspace.error_orders``; ``null`` where none is measurable).
    Top level: ``singular_points``, and ``gci`` (the global
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
        entry["resolution_error_order"] = wmap.error_orders.get(q)
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
                          "resolution_error_order": wmap.gci_error_order,
                          "definition": "mean of 1 / condition number over the feasible points "
                                        "(Gosselin and Angeles 1991); singular points count 0"}
    return json_safe(summary)


def write_stats_json(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", quantities=None,
                     name: str = "path") -> Path:
    """``stats_summary`` as a JSON file."""
    check_suffix(path, (".json",), name)
    summary = stats_summary(wmap, device=device, quantities=quantities)
    return write_text(path, dumps(summary) + "\n", name=name)


#: The figures of a statistics CSV row (``metrics.workspace.FIGURES``: those with a resolution
#: error), each followed by its ``<figure>_resolution_error`` column.
STATS_FIGURES = FIGURES


STATS_CSV_COLUMNS = (("quantity", "unit")
                     + tuple(c for f in STATS_FIGURES for c in (f, f"{f}_resolution_error"))
                     + ("count", "singular_points", "unbounded"))


def write_stats_csv(wmap: WorkspaceMap, path: str | os.PathLike, *, quantities=None, name: str = "path") -> Path:
    """One row per quantity: ``STATS_CSV_COLUMNS``, then ``argmin_<c>_mm`` and ``argmax_<c>_mm``.

    Each figure (``min`` ... ``p95``) is followed by its estimated error from the grid's
    resolution (``<figure>_resolution_error``, the ``resolution_error`` of ``stats_summary``
    and ``isoforce stats --json``), in the row's ``unit`` (``1`` for a dimensionless
    quantity). An error cell is empty where there is no estimate (an unbounded maximum, whose
    cell reads ``inf`` and whose ``unbounded`` reads ``true``). The argmin/argmax columns cover
    every task coordinate ``c`` (``x``, ``y``, ...), as the extremes are points in task space.
    Floats are the shortest decimal that reads back as the same float64.

    Parameters
    ----------
    wmap : WorkspaceMap
        A map (kept or streamed).
    path : str or PathLike
        A ``.csv`` file.
    quantities : sequence of str, optional
        The rows, in order (default every quantity with statistics).
    name : str
        The argument name for error messages.

    Returns
    -------
    Path
        ``path``.
    """
    check_suffix(path, (".csv",), name)
    names = list(wmap.stats) if quantities is None else list(quantities)
    errors = resolution_error(wmap)
    coords = list(wmap.task_names)
    m = len(coords)
    header = list(STATS_CSV_COLUMNS) + [f"argmin_{c}_mm" for c in coords] + [f"argmax_{c}_mm" for c in coords]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for q in names:
        s = wmap.stats[q]
        err = errors.get(q) or {}
        argmin = list(s.argmin) or [float("nan")] * m
        argmax = list(s.argmax) or [float("nan")] * m
        figures = []
        for f in STATS_FIGURES:
            e = err.get(f, float("nan"))
            figures += [format_cell(getattr(s, f)), "" if e is None or np.isnan(e) else format_cell(e)]
        writer.writerow([q, QUANTITIES[q].unit or "1"] + figures
                        + [str(s.count), str(s.singular_points), "true" if s.unbounded else "false"]
                        + [format_cell(v * 1e3) for v in argmin + argmax])
    return write_text(path, buffer.getvalue(), name=name)


def write_stats(wmap: WorkspaceMap, path: str | os.PathLike, *, device: str = "", quantities=None,
                name: str = "path") -> Path:
    """``write_stats_json`` or ``write_stats_csv`` by the suffix of ``path``."""
    suffix = check_suffix(path, STATS_SUFFIXES, name).suffix.lower()
    if suffix == ".json":
        return write_stats_json(wmap, path, device=device, quantities=quantities, name=name)
    return write_stats_csv(wmap, path, quantities=quantities, name=name)
