"""``isoforce bench``: how fast is a workspace map, and how does it compare with pycapacity?

Prints, from one run: the wall time of the full 1000 x 1000 Inverse3 slice map (IK,
Jacobian, condition number, isotropic and anisotropic force at every feasible point) and
of a 200 x 200 one (median of several runs), time per point, peak memory of the big map
(``tracemalloc``, which numpy reports its buffers to), and pycapacity's time per point for
a force polytope plus its inscribed (Chebyshev) ball on the same Jacobians, next to ours for
the same two results (``polytope_vertices`` + ``isotropic_force``) on the same batch.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics as pystats
import time
import tracemalloc
import warnings

import numpy as np

from app.cli._args import int_at_least
from metrics.isotropy import isotropic_force
from metrics.parallelepiped import polytope_vertices
from metrics.quantities import CORE_QUANTITIES, evaluate
from metrics.workspace import compute_map
from resources import load_preset

DEVICE = "inverse3_prototype"


def _median_map_seconds(mechanism, grid, repeats: int) -> tuple[float, object]:
    result = None
    times = []
    for _ in range(repeats):
        result = compute_map(mechanism, grid, CORE_QUANTITIES)
        times.append(result.seconds)
    return pystats.median(times), result


def _peak_memory_bytes(mechanism, grid) -> int:
    tracemalloc.start()
    try:
        compute_map(mechanism, grid, CORE_QUANTITIES)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _sample_jacobians(mechanism, grid, count: int, seed: int = 0) -> np.ndarray:
    """``count`` Jacobians (count, 3, 3) at random feasible points of ``grid``."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array(grid.lower), np.array(grid.upper)
    fixed = dict(grid.fixed)
    found = []
    while sum(len(f) for f in found) < count:
        pts = np.empty((4 * count, mechanism.task_dim))
        uv = lo + (hi - lo) * rng.random((4 * count, len(grid.axes)))
        for j, name in enumerate(mechanism.task_names):
            pts[:, j] = uv[:, grid.axes.index(name)] if name in grid.axes else fixed[name]
        ev = evaluate(mechanism, pts, ["jacobian"])
        found.append(ev.values["jacobian"][ev.feasible])
    return np.concatenate(found)[:count]


def _pycapacity_per_point(jacs: np.ndarray, t: np.ndarray) -> tuple[float, float] | None:
    """Seconds per point for pycapacity's force polytope + Chebyshev ball, and the worst radius gap."""
    try:
        with warnings.catch_warnings():
            # pycapacity imports numpy.matlib, which warns on import (shown under -W always):
            # the peer's own import, not something a user of bench can act on.
            warnings.simplefilter("ignore", PendingDeprecationWarning)
            import pycapacity.robot as pyc
    except ImportError:
        return None
    ours = isotropic_force(jacs, torque_limits=t)
    start = time.perf_counter()
    radii = []
    for jac in jacs:
        poly = pyc.force_polytope(jac, t, -t)
        radii.append(poly.chebyshev_ball().radii[0])
    seconds = (time.perf_counter() - start) / len(jacs)
    # The polytope is centrally symmetric, so its Chebyshev ball is centred at 0: same radius.
    gap = float(np.max(np.abs(np.array(radii) - ours) / ours))
    return seconds, gap


def _ours_per_point(jacs: np.ndarray, t: np.ndarray, repeats: int = 5, batch: int = 30000) -> float:
    """Seconds per point for our vertices + inscribed radius on the same Jacobians (batched).

    The Jacobians are repeated up to ``batch`` rows: a map hands the metrics tens of
    thousands of points per call, and a batch of a few hundred would time numpy's per-call
    overhead rather than the per-point work.
    """
    jacs = np.tile(jacs, (max(1, batch // len(jacs)), 1, 1))
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        polytope_vertices(jacs, torque_limits=t)
        isotropic_force(jacs, torque_limits=t)
        times.append(time.perf_counter() - start)
    return pystats.median(times) / len(jacs)


def run_bench(repeats: int = 5, pycapacity_points: int = 300) -> dict:
    """Measure everything; return the figures as a dict (seconds, bytes)."""
    preset = load_preset(DEVICE)
    mech = preset.mechanism
    full = preset.grid.with_resolution(1000)
    small = preset.grid.with_resolution(200)
    compute_map(mech, small, CORE_QUANTITIES)          # warm up the pool and caches
    full_s, full_map = _median_map_seconds(mech, full, repeats)
    small_s, small_map = _median_map_seconds(mech, small, max(repeats, 9))
    peak = _peak_memory_bytes(mech, full)
    jacs = _sample_jacobians(mech, full, pycapacity_points)
    t = mech.torque_limits()
    ours = _ours_per_point(jacs, t)
    theirs = _pycapacity_per_point(jacs, t)
    return {
        "device": DEVICE,
        "cores": os.cpu_count(),
        "map_1000": {"seconds": full_s, "points": 10**6, "feasible_points": full_map.feasible_points,
                     "seconds_per_point": full_s / 10**6,
                     "seconds_per_feasible_point": full_s / full_map.feasible_points},
        "map_200": {"seconds": small_s, "points": 200 * 200, "feasible_points": small_map.feasible_points},
        "peak_memory_bytes": peak,
        "same_jacobians": {
            "points": len(jacs),
            "isoforce_seconds_per_point": ours,
            "pycapacity_seconds_per_point": theirs[0] if theirs else None,
            "speedup": theirs[0] / ours if theirs else None,
            "map_speedup": theirs[0] / (full_s / full_map.feasible_points) if theirs else None,
            "max_relative_radius_difference": theirs[1] if theirs else None,
        },
    }


def format_bench(r: dict) -> str:
    s = r["same_jacobians"]
    lines = [
        f"isoforce bench: {r['device']}, {r['cores']} cores (median of repeated runs)",
        f"  1000 x 1000 map : {r['map_1000']['seconds'] * 1e3:8.1f} ms   "
        f"({r['map_1000']['seconds_per_point'] * 1e9:.0f} ns/point, "
        f"{r['map_1000']['seconds_per_feasible_point'] * 1e9:.0f} ns/feasible point, "
        f"{r['map_1000']['feasible_points']} feasible)",
        f"  200 x 200 map   : {r['map_200']['seconds'] * 1e3:8.2f} ms",
        f"  peak memory     : {r['peak_memory_bytes'] / 2**20:8.1f} MiB (1000 x 1000 map, tracemalloc)",
        f"  polytope + inscribed ball on the same {s['points']} Jacobians:",
        f"    isoforce      : {s['isoforce_seconds_per_point'] * 1e9:10.1f} ns/point (the same Jacobians repeated "
        f"to a batch of 30000)",
    ]
    if s["pycapacity_seconds_per_point"] is None:
        lines.append("    pycapacity    : not installed (pip install 'isoforce[bench]')")
    else:
        lines += [
            f"    pycapacity    : {s['pycapacity_seconds_per_point'] * 1e6:10.1f} us/point "
            f"(force_polytope + chebyshev_ball, one point at a time)",
            f"    ratio         : {s['speedup']:10.0f} x  (full map per feasible point vs pycapacity: "
            f"{s['map_speedup']:.0f} x)",
            f"    radii agree to: {s['max_relative_radius_difference']:.1e} relative",
        ]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    result = run_bench(repeats=args.repeats, pycapacity_points=args.points)
    if args.json:
        print(json.dumps(result, allow_nan=False))
    else:
        print(format_bench(result))
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("bench", help="time workspace maps and compare with pycapacity",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--repeats", type=int_at_least(1), default=5, help="runs per map timing (median reported)")
    p.add_argument("--points", type=int_at_least(1), default=300, help="Jacobians for the pycapacity comparison")
    p.set_defaults(func=run)
