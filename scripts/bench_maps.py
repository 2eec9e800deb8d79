"""Wall time of every shipped preset's default workspace map, best of several runs.

Usage, from the repository root::

    python scripts/bench_maps.py                      # every preset, best of 3, a table
    python scripts/bench_maps.py --json               # one JSON object
    python scripts/bench_maps.py twin_pantograph stewart_platform --repeats 5
    python scripts/bench_maps.py --quantities app     # the app's statistics panel set

For each preset of ``resources.list_presets()`` the script runs ``metrics.workspace.compute_map``
on the preset's own grid (``preset.grid``) with the quantity set of ``isoforce stats``
(``metrics.quantities.summary_quantities``: condition number, anisotropic and isotropic force,
1 / condition number, and the moment capabilities of a device with orientation freedoms, and the
sensor resolutions where modelled) or, with ``--quantities app``, the app's statistics panel set
(``STATS_QUANTITIES``, which contains the map view's default quantity). ``keep=False`` as
``isoforce stats`` does, the shared thread pool as both clients use it, continuous rating and
gravity off. It prints, per preset, the feasible points, the best wall time of ``--repeats``
runs (``WorkspaceMap.seconds``, the map's own clock: IK, Jacobians, quantities and
statistics; preset loading and process start-up are not in it) and microseconds per feasible
point, and the least process CPU seconds of the runs (all threads; on a machine shared with
other work the wall time can be several times the CPU time). Best-of is the figure least moved
by other load on a shared machine; the median is printed beside it so a noisy run shows.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics as pystats
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from metrics.quantities import STATS_QUANTITIES, summary_quantities  # noqa: E402
from metrics.workspace import compute_map  # noqa: E402
from resources import list_presets, load_preset  # noqa: E402


def quantity_set(mechanism, which: str) -> tuple[str, ...]:
    """The quantities timed: ``"stats"`` (``isoforce stats``) or ``"app"`` (the app's panel)."""
    return summary_quantities(mechanism) if which == "stats" else STATS_QUANTITIES


def bench_preset(key: str, repeats: int, which: str, threads: bool) -> dict:
    """Time ``repeats`` default maps of preset ``key``; best and median seconds, us per feasible point."""
    preset = load_preset(key)
    names = quantity_set(preset.mechanism, which)
    times, cpu, feasible = [], [], 0
    for _ in range(repeats):
        start = time.process_time()
        wmap = compute_map(preset.mechanism, preset.grid, names, keep=False, threads=threads)
        cpu.append(time.process_time() - start)
        times.append(wmap.seconds)
        feasible = wmap.feasible_points
    best = min(times)
    return {"preset": key, "resolution": list(preset.grid.resolution), "points": int(math.prod(preset.grid.resolution)),
            "feasible_points": int(feasible), "seconds": best, "median_seconds": pystats.median(times),
            "cpu_seconds": min(cpu),
            "us_per_feasible_point": (1e6 * best / feasible) if feasible else None, "quantities": list(names)}


def table(rows: list[dict]) -> str:
    head = (f"{'preset':28s} {'grid':>13s} {'feasible':>9s} {'best s':>8s} {'median s':>9s} {'cpu s':>7s} "
            f"{'us/feasible':>12s}")
    lines = [head, "-" * len(head)]
    for r in rows:
        us = "-" if r["us_per_feasible_point"] is None else f"{r['us_per_feasible_point']:.2f}"
        grid = " x ".join(map(str, r["resolution"]))
        lines.append(f"{r['preset']:28s} {grid:>13s} {r['feasible_points']:9d} {r['seconds']:8.3f} "
                     f"{r['median_seconds']:9.3f} {r['cpu_seconds']:7.3f} {us:>12s}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("presets", nargs="*", help="preset keys (default: every shipped preset)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per preset; the best is reported (default 3)")
    parser.add_argument("--quantities", choices=("stats", "app"), default="stats",
                        help="quantity set: isoforce stats's (default) or the app's statistics panel")
    parser.add_argument("--no-threads", action="store_true", help="one chunk at a time (compute_map threads=False)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    known = list_presets()
    keys = args.presets or known
    for key in keys:
        if key not in known:
            parser.error(f"unknown preset {key!r}; known: {', '.join(known)}")
    rows = [bench_preset(k, args.repeats, args.quantities, not args.no_threads) for k in keys]
    if args.json:
        print(json.dumps({"repeats": args.repeats, "quantity_set": args.quantities, "threads": not args.no_threads,
                          "cpus": os.cpu_count(), "load_average": list(os.getloadavg()), "maps": rows}, indent=2))
    else:
        print(f"best of {args.repeats} runs; quantity set {args.quantities!r}; threads {not args.no_threads}; "
              f"{os.cpu_count()} CPUs, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
