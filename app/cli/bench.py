"""``isoforce bench``: how fast is a workspace map, and how does it compare with pycapacity?

Prints, from one run: the wall time of the full 1000 x 1000 Inverse3 slice map (IK,
Jacobian, condition number, isotropic and anisotropic force at every feasible point) and
of a 200 x 200 one (median of several runs), time per point, peak memory of the big map
(``tracemalloc``, which numpy reports its buffers to), and pycapacity's time per point for
a force polytope plus its inscribed (Chebyshev) ball on the same Jacobians, next to ours for
the same two results (``polytope_vertices`` + ``isotropic_force``) on the same batch.

The same 1000 x 1000 map is also computed by a plain numpy reference (``numpy_reference_map``:
the model's numpy IK and J, ``numpy.linalg`` SVD and inverse, whole-array statistics, one
thread), interleaved with the library's map so that both see the same load; the ratio of each
pair is reported (``map_1000.reference_ratio``). ``families`` times each family's default map with a
compiled kernel (``FAMILY_DEVICES``: the core quantities on the preset's own grid) against the same
map on the numpy quantity graph, interleaved the same way. ``compile`` gives the seconds this process spent
loading the compiled kernels (numba's import and its cache), and, measured in a fresh process
with an empty cache directory, what the first command after an install pays without a warmed
cache (``cold_seconds``).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics as pystats
import subprocess
import sys
import tempfile
import time
import tracemalloc
import warnings

import numpy as np

from app.cli._args import int_at_least
from metrics import kernels
from metrics.isotropy import isotropic_force
from metrics.parallelepiped import polytope_vertices
from metrics.quantities import CORE_QUANTITIES, evaluate
from metrics.torque_box import sign_patterns
from metrics.workspace import compute_map
from resources import load_preset

DEVICE = "inverse3_prototype"
#: A preset of each family with a compiled kernel (``metrics.kernels.FAMILIES``) and every other shipped
#: preset of those families whose grid differs: timed at their own default grids (``family_maps``).
FAMILY_DEVICES = ("inverse3_prototype", "fivebar_singh", "haply_2diy", "phantom_premium_15", "phantom_omni",
                  "woodenhaptics", "novint_falcon")


def _median_map_seconds(mechanism, grid, repeats: int) -> tuple[float, object]:
    result = None
    times = []
    for _ in range(repeats):
        result = compute_map(mechanism, grid, CORE_QUANTITIES)
        times.append(result.seconds)
    return pystats.median(times), result


def numpy_reference_map(mechanism, grid) -> tuple[float, dict]:
    """The map's core quantities and their statistics in plain numpy, in one thread; (seconds, figures).

    What the map computes, written the obvious way: the model's numpy IK, limits and J on the
    whole grid at once, ``numpy.linalg`` for the singular values and the inverse, the vertex
    norms from the eight sign patterns, and whole-array statistics (``numpy.quantile``).
    """
    start = time.perf_counter()
    pts = grid.points(mechanism.task_names).reshape(-1, mechanism.task_dim)
    q, ok = mechanism.inverse(pts)
    feasible = ok.copy()
    feasible[ok] = mechanism.feasible(q[ok], pts[ok])
    jac = mechanism.jacobian(q[feasible], pts[feasible])
    t = mechanism.torque_limits()
    sv = np.linalg.svd(jac, compute_uv=False)
    ref = np.swapaxes(np.linalg.inv(jac), -1, -2) * t
    verts = ref @ sign_patterns(mechanism.n_joints).T
    values = {"condition_number": sv[:, 0] / sv[:, -1],
              "isotropic_force": np.min(t / np.linalg.norm(jac, axis=-2), axis=-1),
              "anisotropic_force": np.sqrt(np.max(np.sum(verts * verts, axis=-2), axis=-1))}
    figures = {name: (v.min(), v.max(), int(v.argmin()), int(v.argmax()), v.mean(), v.std(ddof=1),
                      *np.quantile(v, [0.05, 0.5, 0.95], method="inverted_cdf")) for name, v in values.items()}
    return time.perf_counter() - start, figures


def _reference_ratios(mechanism, grid, repeats: int) -> dict:
    """The library's map and the numpy reference, interleaved ``repeats`` times; their times and ratios."""
    ours, theirs = [], []
    for _ in range(repeats):
        ours.append(compute_map(mechanism, grid, CORE_QUANTITIES).seconds)
        theirs.append(numpy_reference_map(mechanism, grid)[0])
    ratios = [a / b for a, b in zip(ours, theirs)]
    return {"reference_seconds": pystats.median(theirs), "reference_ratio": pystats.median(ratios),
            "reference_ratios": ratios}


def family_maps(repeats: int) -> dict:
    """Each of ``FAMILY_DEVICES``' default map of the core quantities: compiled, and on the numpy graph.

    The two runs alternate ``repeats`` times (so both see the same load); medians and the median ratio.
    """
    from kinematics.registry import kind_of

    out = {}
    for key in FAMILY_DEVICES:
        preset = load_preset(key)
        mech, grid = preset.mechanism, preset.grid
        compute_map(mech, grid.with_resolution(20), CORE_QUANTITIES)      # the family's kernels loaded
        ours, theirs = [], []
        for _ in range(repeats):
            ours.append(compute_map(mech, grid, CORE_QUANTITIES).seconds)
            with kernels.use_compiled(False):
                theirs.append(compute_map(mech, grid, CORE_QUANTITIES).seconds)
        out[key] = {"kind": kind_of(mech), "resolution": [int(n) for n in grid.resolution],
                    "seconds": pystats.median(ours), "numpy_graph_seconds": pystats.median(theirs),
                    "ratio": pystats.median([a / b for a, b in zip(ours, theirs)])}
    return out


_COLD = """
import time
start = time.perf_counter()
from metrics import kernels
from resources import load_preset
preset = load_preset("inverse3_prototype")
from metrics.workspace import compute_map
compute_map(preset.mechanism, preset.grid.with_resolution(20), ("condition_number", "isotropic_force"))
print(kernels.compile_seconds())
"""


def compile_cost() -> dict:
    """Seconds spent on the compiled kernels: in this process (cache loads), and cold (an empty cache)."""
    cold = None
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        proc = subprocess.run([sys.executable, "-c", _COLD], env=env, capture_output=True, text=True, timeout=600)
        if proc.returncode == 0:
            cold = float(proc.stdout.split()[-1])
    return {"seconds": kernels.compile_seconds(), "cold_seconds": cold, "kernels": kernels.enabled()}


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
    compute_map(mech, small, CORE_QUANTITIES)          # warm up the pool and caches (and load the kernels)
    loaded = kernels.compile_seconds()
    full_s, full_map = _median_map_seconds(mech, full, repeats)
    reference = _reference_ratios(mech, full, repeats)
    small_s, small_map = _median_map_seconds(mech, small, max(repeats, 9))
    peak = _peak_memory_bytes(mech, full)
    jacs = _sample_jacobians(mech, full, pycapacity_points)
    t = mech.torque_limits()
    ours = _ours_per_point(jacs, t)
    theirs = _pycapacity_per_point(jacs, t)
    families = family_maps(repeats)
    return {
        "device": DEVICE,
        "cores": os.cpu_count(),
        "map_1000": {"seconds": full_s, "points": 10**6, "feasible_points": full_map.feasible_points,
                     "seconds_per_point": full_s / 10**6,
                     "seconds_per_feasible_point": full_s / full_map.feasible_points, **reference},
        "compile": {**compile_cost(), "seconds": loaded},
        "map_200": {"seconds": small_s, "points": 200 * 200, "feasible_points": small_map.feasible_points},
        "peak_memory_bytes": peak,
        "families": families,
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
        f"  numpy reference : {r['map_1000']['reference_seconds'] * 1e3:8.1f} ms   (the same map in plain numpy, "
        f"one thread; ratio {r['map_1000']['reference_ratio']:.3f}, per run "
        f"{', '.join(f'{x:.3f}' for x in r['map_1000']['reference_ratios'])})",
        f"  200 x 200 map   : {r['map_200']['seconds'] * 1e3:8.2f} ms",
        f"  kernels loaded  : {r['compile']['seconds']:8.2f} s    (this process; cold, empty cache: "
        f"{_seconds(r['compile']['cold_seconds'])}; compiled kernels {'on' if r['compile']['kernels'] else 'off'})",
        f"  peak memory     : {r['peak_memory_bytes'] / 2**20:8.1f} MiB (1000 x 1000 map, tracemalloc)",
        "  default maps of each family, compiled / numpy graph (core quantities):",
        *(f"    {key:<19}: {f['seconds'] * 1e3:8.1f} ms / {f['numpy_graph_seconds'] * 1e3:8.1f} ms = "
          f"{f['ratio']:.3f}  ({f['kind']}, {' x '.join(map(str, f['resolution']))})"
          for key, f in r["families"].items()),
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


def _seconds(value: float | None) -> str:
    return "not measured" if value is None else f"{value:.2f} s"


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
