"""The figure of ``isoforce compare``: the devices' isotropic-force distributions on one axis.

Built on ``matplotlib.figure.Figure`` with an Agg canvas (no pyplot, no display), like
``app.plots.figures``; written through ``app.plots.figures.save_figure`` (``app.files.export.atomic_write``).
A streamed map keeps quantiles, not the values, so each box is drawn from them: the box
spans the 5th to 95th percentile, the line is the median, the diamond the mean, and the
triangle the global minimum (paper 000's "global maximum isotropic force").
"""
from __future__ import annotations

import math
import textwrap
from typing import Any, Sequence

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: Above this ratio of the largest shown value to the smallest, the force axis is logarithmic.
LOG_RATIO = 30.0
#: Characters per line of a device's name under its box.
LABEL_WIDTH = 16


def _loading_words(rows: Sequence[dict[str, Any]]) -> str:
    """``"continuous rating, gravity off"``: the loading the rows share (``device_summary``'s ``loading``)."""
    loading = rows[0].get("loading") if rows else None
    if not loading:
        return "continuous rating, gravity off"
    gravity = loading["gravity"]
    where = "gravity off" if gravity == "off" else f"gravity {gravity.get('mounting') or 'on'}"
    return f"{loading['rating']} rating, {where}"


def _regions(rows: Sequence[dict[str, Any]]) -> str:
    """What the statistics are over: 2D slices (areas) or 3D boxes (volumes)."""
    kinds = {row["workspace"]["kind"] for row in rows if "workspace" in row}
    return "3D boxes, volumes" if kinds == {"volume"} else "2D slices, areas" if kinds == {"area"} \
        else "slices and boxes"


def compare_figure(rows: Sequence[dict[str, Any]], *, dpi: int = 150) -> Figure:
    """Box per device from its isotropic-force quantiles, global minimum marked.

    Parameters
    ----------
    rows : sequence of dict
        ``app.cli.compare.device_summary`` results: ``name``, ``key``, ``at_zero_moment`` and
        ``isotropic_force`` with ``min``, ``p05``, ``median``, ``mean``, ``p95`` (N; ``nan``
        where a device has no feasible point).
    dpi : int
        Resolution of raster output.

    Returns
    -------
    Figure
        One axis, one box per device, an Agg canvas attached.
    """
    width = max(5.0, 1.3 * len(rows) + 2.0)
    fig = Figure(figsize=(width, 4.6), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    boxes, labels, shown = [], [], []
    for i, row in enumerate(rows):
        s = row["isotropic_force"]
        label = textwrap.fill(row["name"], LABEL_WIDTH) + ("\n(at zero moment)" if row["at_zero_moment"] else "")
        labels.append(label)
        if not all(math.isfinite(s[k]) for k in ("min", "p05", "median", "p95")):
            boxes.append(None)
            continue
        boxes.append({"label": label, "med": s["median"], "q1": s["p05"], "q3": s["p95"],
                      "whislo": s["p05"], "whishi": s["p95"], "mean": s["mean"], "fliers": []})
        shown += [s["min"], s["p95"]]
    positions = [i + 1 for i, b in enumerate(boxes) if b is not None]
    stats = [b for b in boxes if b is not None]
    if stats:
        ax.bxp(stats, positions=positions, showmeans=True, showcaps=False, widths=0.5, patch_artist=True,
               boxprops={"facecolor": "#c6dbef", "edgecolor": "#08519c"},
               medianprops={"color": "#08519c", "linewidth": 2},
               meanprops={"marker": "D", "markerfacecolor": "white", "markeredgecolor": "#08519c"},
               whiskerprops={"visible": False})
        mins = [rows[p - 1]["isotropic_force"]["min"] for p in positions]
        ax.scatter(positions, mins, marker="v", s=60, color="#cb181d", zorder=5, label="global minimum")
        for p, v, row in zip(positions, mins, (rows[p - 1] for p in positions)):
            # A minimum of 0 (a direct singularity in the map) sits on the axis: its label goes
            # above it, and says why it is 0.
            zero = v == 0.0
            text = "0 N (singular)" if zero and row["isotropic_force"].get("min_vanishes") else f"{v:.3g} N"
            ax.annotate(text, (p, v), xytext=(8, 6 if zero else -4), textcoords="offset points", fontsize=8,
                        color="#cb181d")
    for i, b in enumerate(boxes):
        if b is None:
            ax.text(i + 1, 0.5, "no feasible point", transform=ax.get_xaxis_transform(), ha="center",
                    fontsize=8, color="0.4")
    positive = [v for v in shown if v > 0]
    if positive and max(positive) / min(positive) > LOG_RATIO:
        ax.set_yscale("log")
    elif positive:
        ax.set_ylim(bottom=0.0)
    ax.set_xticks(range(1, len(rows) + 1), labels, fontsize=8)
    ax.set_xlim(0.4, len(rows) + 0.6)
    ax.set_ylabel("maximum isotropic force (N)")
    ax.set_title(f"Isotropic force over each device's workspace\n{_loading_words(rows)}\n"
                 f"each over its own map ({_regions(rows)})\n"
                 "box: 5th-95th percentile, line: median, diamond: mean", fontsize=9)
    ax.grid(axis="y", alpha=0.3)
    if stats:
        ax.legend(loc="best", fontsize=8)
    return fig
