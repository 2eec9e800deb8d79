"""Cost of the dynamic quantities on a map: dynamic / static wall time, per preset, same run.

Usage, from the repository root::

    python scripts/bench_dynamics.py                  # every preset with a mass model, a table
    python scripts/bench_dynamics.py --json           # one JSON object
    python scripts/bench_dynamics.py phantom_premium_15 stewart_platform --repeats 5

For each preset with a mass model the script times ``metrics.workspace.compute_map`` on the
preset's own grid twice, interleaved run by run so both see the same load: the *static* set
(``isoforce stats``'s quantities without the dynamic ones) and the *dynamic* set (the same plus
``DYNAMIC_SUMMARY``: the lightest and heaviest apparent mass and the isotropic acceleration).
One thread (``threads=False``), ``keep=False``, continuous rating, gravity off. It reports the
best of ``--repeats`` of each, wall (the map's own clock, ``WorkspaceMap.seconds``) and process
CPU seconds, and their ratios (issue 22 asks for at most 2). Wall times on a shared machine move
with other load; the ratio of two runs taken side by side moves less, the CPU ratio least.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from metrics.quantities import DYNAMIC_SUMMARY, SPEED_SUMMARY, summary_quantities  # noqa: E402
from metrics.workspace import compute_map  # noqa: E402
from resources import list_presets, load_preset  # noqa: E402


def bench_preset(key: str, repeats: int) -> dict:
    """Best seconds of the static and the dynamic map of preset ``key``, and their ratio."""
    preset = load_preset(key)
    # The velocity (a preset with motor speeds) is kinematic, not a mass quantity: in neither set.
    dynamic = tuple(q for q in summary_quantities(preset.mechanism) if q not in SPEED_SUMMARY)
    static = tuple(q for q in dynamic if q not in DYNAMIC_SUMMARY)
    times: dict[str, list[float]] = {"static": [], "dynamic": []}
    cpu: dict[str, list[float]] = {"static": [], "dynamic": []}
    feasible = 0
    for _ in range(repeats):
        for name, names in (("static", static), ("dynamic", dynamic)):
            start = time.process_time()
            wmap = compute_map(preset.mechanism, preset.grid, names, keep=False, threads=False)
            cpu[name].append(time.process_time() - start)
            times[name].append(wmap.seconds)
            feasible = wmap.feasible_points
    best = {name: min(t) for name, t in times.items()}
    least = {name: min(t) for name, t in cpu.items()}
    return {"preset": key, "resolution": list(preset.grid.resolution), "feasible_points": int(feasible),
            "static_seconds": best["static"], "dynamic_seconds": best["dynamic"],
            "ratio": best["dynamic"] / best["static"], "static_cpu_seconds": least["static"],
            "dynamic_cpu_seconds": least["dynamic"], "cpu_ratio": least["dynamic"] / least["static"],
            "static_runs": times["static"], "dynamic_runs": times["dynamic"]}


def table(rows: list[dict]) -> str:
    head = (f"{'preset':28s} {'grid':>13s} {'feasible':>9s} {'static ms':>10s} {'dynamic ms':>11s} {'ratio':>6s}"
            f" {'cpu ratio':>9s}")
    lines = [head, "-" * len(head)]
    for r in rows:
        grid = " x ".join(map(str, r["resolution"]))
        lines.append(f"{r['preset']:28s} {grid:>13s} {r['feasible_points']:9d} {1e3 * r['static_seconds']:10.1f} "
                     f"{1e3 * r['dynamic_seconds']:11.1f} {r['ratio']:6.2f} {r['cpu_ratio']:9.2f}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("presets", nargs="*", help="preset keys (default: every shipped preset with a mass model)")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each set; the best is reported (default 3)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    known = list_presets()
    for key in args.presets:
        if key not in known:
            parser.error(f"unknown preset {key!r}; known: {', '.join(known)}")
    keys = args.presets or [k for k in known if load_preset(k).mechanism.has_mass_model]
    rows = [bench_preset(k, args.repeats) for k in keys]
    if args.json:
        print(json.dumps({"repeats": args.repeats, "cpus": os.cpu_count(), "load_average": list(os.getloadavg()),
                          "maps": rows}, indent=2))
    else:
        print(f"best of {args.repeats} runs, one thread; {os.cpu_count()} CPUs, load average "
              f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
