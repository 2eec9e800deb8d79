"""Text tables of a convergence study (``metrics.convergence``), for the command line.

Presentation only: the study itself is numbers (``ConvergenceStudy``, ``to_dict`` for JSON).
"""
from __future__ import annotations

import math

from metrics.convergence import FIGURES, ConvergenceStudy, resolution_label


def format_table(study: ConvergenceStudy) -> str:
    """Text tables: the rungs, then per quantity each figure's error against the reference.

    Columns ``min-exact``/``max-exact`` give the error against a usable exact value.
    ``-`` marks an error that is not finite (an ``inf`` figure) or not defined.
    """
    ref = study.reference
    lines = [f"reference: {resolution_label(ref.resolution)} ({ref.points:,} points, "
             f"{ref.feasible_points:,} feasible, {ref.seconds:.3f} s)", "",
             f"{'resolution':>13} {'points':>11} {'feasible':>11} {'seconds':>9}"]
    for r in study.rows:
        lines.append(f"{resolution_label(r.resolution):>13} {r.points:>11,} {r.feasible_points:>11,} "
                     f"{r.seconds:>9.4f}" + ("  (reference)" if r.is_reference else ""))
    for q in study.quantities:
        unit = study.units.get(q, "")
        lines += ["", f"{q}" + (f" [{unit}]" if unit else "") + ": |figure - reference figure|"]
        figs = ref.figures[q]
        lines.append("  reference: " + "  ".join(f"{f} {_num(figs[f])}" for f in FIGURES))
        ex = study.exact.get(q, {})
        for f, e in ex.items():
            lines.append(f"  exact {f}: {_num(e.value)}  [{e.status}] {e.note}")
        ex_figs = [f for f in ("min", "max") if f in ex and ex[f].usable]
        header = f"  {'resolution':>13} {'seconds':>9}" + "".join(f" {f:>10}" for f in FIGURES)
        header += "".join(f" {f + '-exact':>10}" for f in ex_figs)
        lines.append(header)
        for r in study.rows:
            row = f"  {resolution_label(r.resolution):>13} {r.seconds:>9.4f}"
            row += "".join(f" {'(ref)' if r.is_reference else _err(r.abs_errors[q][f]):>10}" for f in FIGURES)
            row += "".join(f" {_err(r.exact_errors[q].get(f, math.nan)):>10}" for f in ex_figs)
            lines.append(row)
        rates, ex_rates = study.rates[q], study.exact_rates.get(q, {})
        lines.append(f"  {'rate p':>13} {'':>9}" + "".join(f" {_rate(rates[f]):>10}" for f in FIGURES)
                     + "".join(f" {_rate(ex_rates.get(f, math.nan)):>10}" for f in ex_figs)
                     + "   (error ~ n^-p, n points per axis)")
    return "\n".join(lines)


def _num(value: float) -> str:
    return f"{value:.7g}" if math.isfinite(value) else str(value)


def _err(value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return "0" if value == 0.0 else f"{value:.2e}"


def _rate(value: float) -> str:
    return f"{value:.2f}" if math.isfinite(value) else "-"
