"""``isoforce convergence``: error against run time of a device's workspace map.

::

    isoforce convergence DEVICE [--quantity Q ...] [--resolutions 50,100,200,...]
                                [--tol T] [--exact-rtol R] [--out plot.png] [--json]

Runs the device's default map at a ladder of resolutions (``n`` points on the map's longest
axis, the other axes in the preset's proportion) and prints, for each rung, the run time
and the error of every global figure (min, max, mean, SD of each quantity) against the
finest rung, and against an exact value where one exists (global min and max located by
adaptive refinement). Then it refines the global minimum isotropic force (paper 000's
"global maximum isotropic force") to ``--tol`` N and sets its evaluations and run time
beside those of the uniform rung that first reaches the same tolerance for good.

``--out`` writes a log-log plot of relative error against seconds (one line per figure,
one panel per quantity; .png, .svg or .pdf), atomically. ``--json`` prints exactly one JSON
object (nan/inf as null) and nothing else on stdout.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from app.cli._args import MapJob, UsageError, add_max_time_argument, check_job, job_points
from app.cli._format import grid_box
from app.cli._progress import progress_for
from app.files.export import FIGURE_SUFFIXES, atomic_write, check_output, check_suffix
from app.logic.convergence_text import format_table
from metrics.convergence import (
    DEFAULT_LADDER,
    FIGURES,
    ConvergenceStudy,
    Refinement,
    UniformMatch,
    convergence_study,
    refine_global_minimum,
    uniform_grid_for,
)
from metrics.quantities import QUANTITIES, STATS_QUANTITIES

#: The quantity whose global minimum is refined (paper 000's "global maximum isotropic force").
REFINED = "isotropic_force"
DEFAULT_TOL = 1e-3
DEFAULT_EXACT_RTOL = 1e-5
#: Budget of the tighter refinement that serves as the exact value when the study has none.
REFERENCE_BUDGET = 1_500_000


def register(subparsers) -> None:
    """Add the ``convergence`` subcommand; its ``func`` is ``run``."""
    p = subparsers.add_parser(
        "convergence", help="error of the global figures against run time, over a ladder of resolutions",
        description="Run the device's map at a ladder of resolutions and print, for each, the run time and "
                    "the error of every global figure (min, max, mean, SD) against the finest run and "
                    "against exact extremes; then refine the global minimum isotropic force to --tol and "
                    "compare its cost with the uniform grid that reaches the same tolerance.")
    p.add_argument("device", metavar="DEVICE", help="preset key (see `isoforce devices`) or path to a .toml")
    p.add_argument("--quantity", action="append", metavar="Q", default=None,
                   help=f"quantity to study (repeat, or comma-separate); default {', '.join(STATS_QUANTITIES)}")
    p.add_argument("--resolutions", metavar="N,N,...", default=",".join(str(n) for n in DEFAULT_LADDER),
                   help="points on the longest map axis of each rung, comma-separated; the finest is the "
                        f"reference (default {','.join(str(n) for n in DEFAULT_LADDER)})")
    p.add_argument("--tol", metavar="T", default=str(DEFAULT_TOL),
                   help=f"absolute tolerance in N of the refined global minimum isotropic force "
                        f"(default {DEFAULT_TOL})")
    p.add_argument("--exact-rtol", metavar="R", default=str(DEFAULT_EXACT_RTOL),
                   help="relative tolerance to which the exact global min and max of each quantity are "
                        f"refined (default {DEFAULT_EXACT_RTOL:g}); 0 skips them")
    p.add_argument("--out", metavar="FILE", help="write the error-against-time plot (.png, .svg or .pdf)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_max_time_argument(p)
    p.set_defaults(func=run)


class _InputError(ValueError):
    pass


def _parse_resolutions(text: str) -> list[int]:
    parts = [p.strip() for p in str(text).split(",") if p.strip()]
    try:
        values = [int(p) for p in parts]
    except ValueError:
        values = []
    if len(values) < 2 or any(v < 2 for v in values) or len(set(values)) != len(values):
        raise _InputError(f"--resolutions needs at least two distinct integers >= 2, comma-separated, got {text!r}")
    return sorted(values)


def _parse_tol(text: str) -> float:
    try:
        tol = float(text)
    except (TypeError, ValueError):
        tol = math.nan
    if not (math.isfinite(tol) and tol > 0.0):
        raise _InputError(f"--tol needs a positive number in N, got {text!r}")
    return tol


def _parse_exact_rtol(text: str) -> float | None:
    try:
        rtol = float(text)
    except (TypeError, ValueError):
        rtol = math.nan
    if not (math.isfinite(rtol) and rtol >= 0.0):
        raise _InputError(f"--exact-rtol needs a number >= 0 (0 skips the exact extremes), got {text!r}")
    return rtol or None


def _parse_quantities(items, mechanism) -> tuple[str, ...]:
    if not items:
        names = list(STATS_QUANTITIES)     # the core quantities and 1 / condition number (its mean is the GCI)
    else:
        names = [q.strip() for item in items for q in item.split(",") if q.strip()]
    out: list[str] = []
    for q in names:
        node = QUANTITIES.get(q)
        if node is None or not node.scalar or node.categorical or (q == "singularity"):
            raise _InputError(f"--quantity: {q!r} has no global figures; choose from "
                              f"{', '.join(n for n, v in QUANTITIES.items() if v.scalar and not v.categorical)}")
        if q not in out:
            out.append(q)
    if REFINED not in out:
        out.append(REFINED)     # the refinement is compared with the ladder's own figures
    return tuple(out)


def run(args: argparse.Namespace) -> int:
    """Run the study; print a table (or one JSON object); return 0, or 2 on bad input."""
    from resources import PresetError, load_preset

    try:
        preset = load_preset(args.device)
    except PresetError as exc:
        print(f"isoforce convergence: error: DEVICE: {exc}", file=sys.stderr)
        return 2
    try:
        ladder = _parse_resolutions(args.resolutions)
        tol = _parse_tol(args.tol)
        exact_rtol = _parse_exact_rtol(args.exact_rtol)
        quantities = _parse_quantities(args.quantity, preset.mechanism)
        target = None
        if args.out is not None:
            target = check_output(args.out, FIGURE_SUFFIXES, "--out")
    except ValueError as exc:
        print(f"isoforce convergence: error: {exc}", file=sys.stderr)
        return 2

    mech, grid = preset.mechanism, preset.grid
    from metrics.budget import BudgetError, check_map
    from metrics.convergence import ladder_resolution
    try:
        # Rungs run one after the other and each map is dropped before the next: the finest counts.
        check_map(mech, ladder_resolution(grid, ladder[-1]), quantities, option="a finest --resolutions rung of")
    except BudgetError as exc:
        print(f"isoforce convergence: error: --resolutions: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    # The rungs' maps, one after another (the refinements after them have their own evaluation budgets).
    finest = ladder[-1]
    jobs = [MapJob(mech, grid.with_resolution(ladder_resolution(grid, n)), quantities, keep_maps=False,
                   points_at=lambda m, n=n: math.prod(ladder_resolution(grid, m if n == finest else n)))
            for n in ladder]
    try:
        job = check_job("convergence", jobs, max_time=args.max_time, option="a finest --resolutions rung of",
                        what=f"the ladder's maps up to {finest}")
    except UsageError as exc:
        print(f"isoforce convergence: error: {exc}", file=sys.stderr)
        return 2
    # The bar's share and time left are the maps' (predicted); the refinements after them are
    # named steps with the time elapsed (their cost is bounded by a budget, not predicted).
    with progress_for("isoforce convergence", job and job.seconds, job_points(jobs), json_out=args.json) as progress:
        study = convergence_study(mech, grid, quantities, ladder, exact_rtol=exact_rtol,
                                  progress=_steps(progress),
                                  map_progress=progress)
        progress.step(f"refine min {REFINED} to {tol:g} N", None)
        refinement = refine_global_minimum(mech, grid, REFINED, tol=tol)
        progress.step(f"the reference minimum of {REFINED}", None)
        exact, exact_source, exact_ok = _exact_minimum(study, mech, grid, tol)
    uniform = uniform_grid_for(study, REFINED, exact=exact, tol=tol)
    if target is not None:
        write_plot(study, target, title=f"{preset.name} ({preset.key})", refinement=refinement, exact=exact)
    if args.json:
        out = {"device": preset.key, "name": preset.name, "study": study.to_dict(),
               "refinement": {"result": refinement.to_dict(), "exact": _finite(exact), "exact_source": exact_source,
                              "exact_certified": exact_ok, "error": _finite(abs(refinement.value - exact)),
                              "uniform": uniform.to_dict()},
               "plot": str(target) if target is not None else None}
        print(json.dumps(out, allow_nan=False))
        return 0
    print(f"{preset.name} ({preset.key}): convergence of the {'-'.join(grid.axes)} map "
          f"({grid_box(grid, preset.mechanism)}); rung n = points on the longest axis")
    print(format_table(study))
    print()
    print(format_refinement(refinement, uniform, exact=exact, exact_source=exact_source, exact_ok=exact_ok,
                            map_quantities=len(study.quantities)))
    if target is not None:
        print(f"\nwrote {target}")
    return 0


def _steps(progress):
    """``convergence_study``'s step messages to ``progress``: a map's share is known, a refinement's not."""
    def say(message: str) -> None:
        if message.startswith("map "):
            progress.step(message)
        else:
            progress.step(message, None)
    return say


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _exact_minimum(study: ConvergenceStudy, mech, grid, tol: float) -> tuple[float, str, bool]:
    """The truth to measure the ``tol`` refinement and the uniform rungs against.

    The study's own exact minimum when certified to tol / 10 or better; else a refinement to
    tol / 10 (budget ``REFERENCE_BUDGET``), flagged if it could not be certified.
    """
    ex = study.exact.get(REFINED, {}).get("min")
    if ex is not None and ex.usable and ex.tol <= tol / 10:
        return ex.value, f"study refinement (+-{ex.tol:.2g})", True
    r = refine_global_minimum(mech, grid, REFINED, tol=tol / 10, max_evaluations=REFERENCE_BUDGET)
    if r.certified:
        return r.value, f"refinement to tol/10 (+-{r.tol:.2g}, {r.evaluations:,} evaluations)", True
    return r.value, (f"refinement to tol/10, NOT certified within {r.evaluations:,} evaluations "
                     f"(true minimum between {r.bound:.7g} and {r.value:.7g})"), False


def format_refinement(r: Refinement, u: UniformMatch, *, exact: float, exact_source: str, exact_ok: bool,
                      map_quantities: int | None = None) -> str:
    """The refinement against the uniform grid, as text.

    ``map_quantities``: the quantities the study's maps computed. A rung's seconds are its whole
    map's (every quantity of the study, with its streamed statistics), the refinement's one
    quantity's search: the time ratio says so rather than pass for a like-for-like comparison.
    """
    unit = QUANTITIES[r.quantity].unit
    of_map = ("" if not map_quantities or map_quantities == 1 else
              f" (its map computes {map_quantities} quantities and their statistics; the refinement 1)")
    pt = ", ".join(f"{v * 1e3:.3f}" for v in r.point)
    lines = [f"adaptive refinement of the global minimum {r.quantity} (tol {r.tol:g} {unit}):",
             f"  refined: {r.value:.7g} {unit} at ({pt}) mm; "
             + (f"certified: true minimum in [{r.bound:.7g}, {r.value:.7g}]" if r.certified
                else f"NOT certified (budget): true minimum in [{r.bound:.7g}, {r.value:.7g}]"),
             f"  cost: {r.evaluations:,} evaluations, {r.seconds:.4f} s (coarse "
             f"{' x '.join(map(str, r.coarse_resolution))}, {r.levels} levels, finest cell "
             f"{' x '.join(f'{s * 1e3:.2g}' for s in r.finest_spacing)} mm)",
             f"  exact: {exact:.9g} {unit} [{exact_source}]; error of the refined value "
             f"{abs(r.value - exact):.2e} {unit}" + ("" if exact_ok else " (against an uncertified reference)")]
    if u.resolution is None:
        lines.append("  uniform grid: no rung has a finite error; cannot compare")
    elif not u.extrapolated:
        lines.append(f"  uniform grid: {' x '.join(map(str, u.resolution))} is the coarsest rung within tol from "
                     f"there on: {u.points:,} evaluations, {u.seconds:.4f} s (error {u.error:.2e} {unit})")
    else:
        lines.append(f"  uniform grid: no rung reaches tol (finest error {u.finest_error:.2e} {unit}); "
                     f"extrapolated at error ~ n^-{u.rate:.2f}: about {' x '.join(map(str, u.resolution))}, "
                     f"{u.points:,.3g} evaluations, {u.seconds:.3g} s")
    if u.points:
        lines.append(f"  ratio: {u.points / max(r.evaluations, 1):,.0f}x fewer evaluations, "
                     f"{u.seconds / max(r.seconds, 1e-9):,.0f}x less time than the uniform grid"
                     + (" (estimate)" if u.extrapolated else "") + of_map)
    if u.lucky:
        lucky = ", ".join(" x ".join(map(str, res)) for res in u.lucky)
        lines.append(f"  (within tol by luck, a node near the minimum, but not for good: {lucky})")
    return "\n".join(lines)


_COLOURS = {"min": "tab:blue", "max": "tab:red", "mean": "tab:green", "sd": "tab:purple", "median": "tab:orange",
            "p05": "tab:cyan", "p95": "tab:brown"}


def write_plot(study: ConvergenceStudy, path: str | Path, *, title: str = "", refinement: Refinement | None = None,
               exact: float | None = None, name: str = "--out") -> Path:
    """Log-log plot of relative error against seconds, one panel per quantity, written atomically.

    Solid lines: error of each figure against the reference (finest) run, over the coarser
    rungs. Dashed: min and max against their exact values, over every rung. A star: the
    refined minimum of ``refinement.quantity`` against ``exact``. matplotlib (Agg) is
    imported here, so the command line needs it only when it draws.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    target = check_suffix(path, FIGURE_SUFFIXES, name)
    qs = study.quantities
    fig = Figure(figsize=(4.2 * len(qs), 4.2), dpi=120, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(qs), squeeze=False, sharey=True)[0]
    drawn_any = False
    for ax, q in zip(axes, qs):
        for f in FIGURES:
            pts = [(r.seconds, r.rel_errors[q][f]) for r in study.rows
                   if not r.is_reference and math.isfinite(r.rel_errors[q][f]) and r.rel_errors[q][f] > 0]
            if pts:
                ax.plot(*zip(*pts), "o-", color=_COLOURS[f], label=f"{f} vs finest", lw=1.4, ms=4)
                drawn_any = True
            value = study.exact_value(q, f) if f in ("min", "max") else None
            if value is not None and math.isfinite(value) and value != 0:
                rows = list(study.rows) + ([] if study.reference in study.rows else [study.reference])
                pts = [(r.seconds, r.exact_errors[q][f] / abs(value)) for r in rows
                       if math.isfinite(r.exact_errors[q].get(f, math.nan)) and r.exact_errors[q][f] > 0]
                if pts:
                    ax.plot(*zip(*pts), "s--", color=_COLOURS[f], label=f"{f} vs exact", lw=1.0, ms=3,
                            alpha=0.8)
                    drawn_any = True
        if refinement is not None and refinement.quantity == q and exact not in (None, 0) and math.isfinite(exact):
            err = abs(refinement.value - exact) / abs(exact)
            ax.plot([refinement.seconds], [max(err, 1e-16)], "*", color="black", ms=13,
                    label=f"refined min, tol {refinement.tol:g} (vs exact)")
            ax.axhline(refinement.tol / abs(exact), color="black", lw=0.8, ls=":",
                       label="tol of the refinement")
            drawn_any = True
        unit = QUANTITIES[q].unit
        ax.set_title(q.replace("_", " ") + (f" [{unit}]" if unit else ""), fontsize=10)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("run time (s)")
        ax.grid(True, which="major", alpha=0.4)
        ax.grid(True, which="minor", alpha=0.12)
    axes[0].set_ylabel("relative error of the global figure")
    handles: dict[str, object] = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    if handles:
        fig.legend(list(handles.values()), list(handles.keys()), loc="outside lower center",
                   ncol=min(len(handles), 4), fontsize=8, frameon=False)
    ref = study.reference
    fig.suptitle(f"{title}: error against run time (reference {' x '.join(map(str, ref.resolution))})"
                 if title else "error against run time", fontsize=11)
    if not drawn_any:
        for ax in axes:
            ax.text(0.5, 0.5, "no finite, non-zero errors", transform=ax.transAxes, ha="center")
    fmt = target.suffix.lower().lstrip(".")
    return atomic_write(target, lambda tmp: fig.savefig(tmp, format=fmt), name=name)
