"""Culling search versus brute force on a real five-bar design sweep: wall time and evaluations.

Usage, from the repository root::

    python scripts/bench_culling.py                  # 10 x 10 x 10 designs, 2 mm workspace grid
    python scripts/bench_culling.py --n 6 --spacing-mm 4 --top 3

The study: planar five-bars (``kinematics.FiveBar``, working mode ``+-``) with the proximal
length a1, distal length a2 and half base a3 on an ``n x n x n`` grid; the workspace is the
grid of points (spacing ``--spacing-mm``) inside a fixed disc (centre (0, 160) mm, radius
50 mm). Each design is evaluated with ``metrics.quantities.evaluate`` on many points at once
(one call per design and sample batch, ``metrics.culling.per_design``). Unreachable points
are ``nan`` and, under the default ``infeasible="fail"``, rule a design out: it must reach
the whole disc. Two objectives, each maximised over the designs:

* ``min``: the global minimum isotropic force over the disc (N), ``min_x f_iso(p, x)``;
* ``ratio``: a GII-style index (paper 001 eq. 11), ``min_x sigma_min(J) / max_x sigma_max(J)``.

For each, brute force and culling run on the same evaluator; the script checks that they
return the same optimum and top-K list (values bit-for-bit) and prints the wall times, the
evaluation counts ((design, point) pairs), the evaluator calls, and the ratios. Evaluations
are what culling saves; each ``evaluate`` call also has a fixed cost of some 0.1 ms, which
is why the wall-time ratio is smaller than the evaluation ratio.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from kinematics import FiveBar  # noqa: E402
from metrics.design.culling import brute_force, culling_search
from metrics.design.evaluator_adapters import per_design  # noqa: E402
from metrics.quantities import evaluate  # noqa: E402

CENTRE = (0.0, 0.160)
RADIUS = 0.050


class Counted:
    """Evaluator wrapper counting calls of the underlying per-design function."""

    def __init__(self, func):
        self.func = func
        self.calls = 0

    def __call__(self, design, samples):
        self.calls += 1
        return self.func(design, samples)


def study(n: int, spacing: float):
    """The designs (a1, a2, a3) in m, their models, and the workspace points (S, 2) in m."""
    a1 = np.linspace(0.08, 0.14, n)
    a2 = np.linspace(0.10, 0.18, n)
    a3 = np.linspace(0.02, 0.06, n)
    grid = np.stack(np.meshgrid(a1, a2, a3, indexing="ij"), -1).reshape(-1, 3)
    mechs = [FiveBar(proximal=p, distal=d, half_base=h) for p, d, h in grid]
    h = np.arange(-RADIUS, RADIUS + 1e-12, spacing)
    pts = np.stack(np.meshgrid(h + CENTRE[0], h + CENTRE[1], indexing="ij"), -1).reshape(-1, 2)
    pts = pts[np.hypot(pts[:, 0] - CENTRE[0], pts[:, 1] - CENTRE[1]) <= RADIUS + 1e-12]
    return grid, mechs, pts


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=10, help="grid steps per link length (designs = n^3)")
    parser.add_argument("--spacing-mm", type=float, default=2.0, help="workspace grid spacing, mm")
    parser.add_argument("--top", type=int, default=5, help="runners-up to list (top K)")
    parser.add_argument("--infeasible", choices=("fail", "skip"), default="fail")
    args = parser.parse_args(argv)
    grid, mechs, pts = study(args.n, args.spacing_mm * 1e-3)
    D, S = len(mechs), len(pts)
    print(f"five-bar sweep: {D} designs (a1 80..140, a2 100..180, a3 20..60 mm, {args.n} steps each) x "
          f"{S} workspace points (disc r = {RADIUS * 1e3:.0f} mm at (0, {CENTRE[1] * 1e3:.0f}) mm, "
          f"{args.spacing_mm:g} mm grid); infeasible = {args.infeasible!r}, top K = {args.top}")

    def isotropic(d, s):
        return evaluate(mechs[d], pts[s], ["isotropic_force"]).values["isotropic_force"]

    def singular(d, s):
        sv = evaluate(mechs[d], pts[s], ["singular_values"]).values["singular_values"]
        return sv[:, -1], sv[:, 0]

    ok = True
    for form, func, label in (("min", isotropic, "global min isotropic force (N)"),
                              ("ratio", singular, "min sigma_min / max sigma_max")):
        print(f"\nobjective {form!r}: {label}")
        print(f"  {'method':<12} {'best value':>12} {'a1, a2, a3 (mm)':>18} {'evaluations':>12} "
              f"{'calls':>7} {'seconds':>8}")
        runs = {}
        for name, method in (("brute force", brute_force), ("culling", culling_search)):
            counted = Counted(func)
            t0 = time.perf_counter()
            r = method(per_design(counted), D, S, form=form, infeasible=args.infeasible, top_k=args.top)
            wall = time.perf_counter() - t0
            runs[name] = (r, counted.calls, wall)
            design = ", ".join(f"{v * 1e3:.1f}" for v in grid[r.design])
            print(f"  {name:<12} {r.value:>12.6g} {design:>18} {r.evaluations:>12d} {counted.calls:>7d} "
                  f"{wall:>8.3f}")
        (b, bcalls, bwall), (c, ccalls, cwall) = runs["brute force"], runs["culling"]
        same = (b.value == c.value and b.design == c.design and np.array_equal(b.top_designs, c.top_designs)
                and np.array_equal(b.top_values, c.top_values))
        ok &= same
        print(f"  identical optimum and top-{args.top} list: {same}")
        print(f"  top {args.top}: " + "; ".join(
            f"({', '.join(f'{v * 1e3:.1f}' for v in grid[d])}) {v:.6g}" for d, v in zip(c.top_designs, c.top_values)))
        print(f"  culling / brute force: evaluations {c.evaluations / b.evaluations:.4f} "
              f"(1 : {b.evaluations / c.evaluations:.0f}), calls {ccalls / bcalls:.3f}, "
              f"wall time {cwall / bwall:.3f} (speed-up x{bwall / cwall:.1f}); "
              f"{c.exact_designs} designs evaluated exactly, {len(c.probes)} probe points")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
