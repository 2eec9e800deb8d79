"""Culling against brute force on design studies small enough for brute force: wall time and
evaluations, on one process and on local worker processes. Also times the full 10^6 x 10^3
five-bar study by culling (``--large``), and paper 001's Table VII at full size, 22,027,824
Twin-Pantograph designs on 2,422,959 samples (``--paper-scale``; figures in docs/paper_scale.md).

    python scripts/bench_optimize.py [--workers N] [--large] [--paper-scale] [--dask]

The Twin-Pantograph rows also print what one design costs with the per-design model evaluator
(``Generic``), with the design-vectorised one (``metrics.design.twin_batch``, compiled) and with
its numpy reference pass.

Every row checks that its ranking (designs and values, the tie order included) equals the
single-process brute force's; a benchmark prints figures, it asserts nothing about time.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from metrics.design import build_study, process_pool, run_study  # noqa: E402
from resources.study_schema import parse_study_text, read_study_file  # noqa: E402

STUDIES = ROOT / "resources" / "studies"


def reduced_large() -> object:
    """``fivebar_large`` with a3 on 10 values: 100 x 100 x 10 = 10^5 designs x 10^3 samples."""
    text = (STUDIES / "fivebar_large.toml").read_text(encoding="utf-8")
    old = "half_base = { min = 5.0, max = 104.0, step = 1.0 }"
    assert old in text
    text = text.replace(old, "half_base = { min = 59.0, max = 104.0, step = 5.0 }")
    return build_study(parse_study_text(text, "fivebar_large.toml (a3 in 59..104 step 5 mm)", "fivebar_medium"))


def twin_one_distance() -> object:
    """``twin_pantograph_distance`` at 25 cm (Table VII's distance): 1,458 designs x 486 samples."""
    return build_study(read_study_file(STUDIES / "twin_pantograph_distance.toml")).runs()[2]


def evaluator_costs(st) -> str:
    """Per-design cost on 8 probe samples (256 designs in one call, as the probes ask) and per-pair
    cost on the whole workspace (4 designs), for the model's evaluator, the design-vectorised one
    (compiled) and its numpy reference pass (``kernels.use_compiled(False)``); CPU time of this
    process, which a loaded machine inflates less than wall time. The compiled kernel is loaded
    (or compiled) before the timing."""
    from metrics import kernels
    from metrics.design.evaluators import Generic
    from metrics.design.twin_batch import TwinBatch
    ids = np.arange(0, st.n_designs, 5)[:256]
    TwinBatch(st)(ids[:2], np.arange(2))
    out = []
    for label, ev, compiled in (("Generic", Generic(st), True), ("TwinBatch", TwinBatch(st), True),
                                ("TwinBatch numpy", TwinBatch(st), False)):
        with kernels.use_compiled(compiled):
            t0 = time.process_time()
            ev(ids, np.arange(8))
            probe = (time.process_time() - t0) / ids.size
            t0 = time.process_time()
            ev(ids[:4], np.arange(st.n_samples))
            pair = (time.process_time() - t0) / (4 * st.n_samples)
        out.append(f"{label}: {1e3 * probe:.4f} ms CPU per design on 8 samples, {1e6 * pair:.2f} us CPU per pair")
    return "; ".join(out)


def cases():
    yield "twin-pantograph force GII, 25 cm, 1458 x 486", twin_one_distance()
    yield "five-bar min isotropic force, 10^5 x 10^3", reduced_large()
    yield "paper 002 Table 1 (count K > 5)", build_study(read_study_file(STUDIES / "fivebar_table1.toml"))
    yield "paper 000 base gear ratio", build_study(read_study_file(STUDIES / "inverse3_gear_ratio.toml"))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local worker processes")
    p.add_argument("--large", action="store_true", help="also time the full fivebar_large study by culling")
    p.add_argument("--paper-scale", action="store_true",
                   help="also time paper 001 Table VII at full size (twin_pantograph_table7) by culling")
    p.add_argument("--dask", action="store_true", help="--paper-scale on a dask LocalCluster of --workers processes")
    args = p.parse_args(argv)
    pool = process_pool(args.workers) if args.workers > 1 else None
    try:
        if pool is not None:      # start the workers before timing anything
            list(pool.map(abs, range(args.workers)))
        print(f"{'study':45s} {'method':12s} {'engine':24s} {'designs x samples':>20s} {'evaluations':>14s} "
              f"{'ratio':>8s} {'wall s':>8s}  same ranking")
        for label, st in cases():
            ref = None
            for method in ("brute_force", "culling"):
                for workers in ((1, args.workers) if args.workers > 1 else (1,)):
                    t0 = time.perf_counter()
                    r = run_study(st, method=method, workers=workers, executor=pool if workers > 1 else None,
                                  with_report=False)
                    wall = time.perf_counter() - t0
                    if ref is None:
                        ref = r
                    same = (np.array_equal(r.top_designs, ref.top_designs)
                            and np.array_equal(r.top_values, ref.top_values))
                    engine = f"{r.engine} ({r.workers}, {r.chunks} chunks)"
                    print(f"{label:45s} {method:12s} {engine:24s} {f'{r.n_designs:,} x {r.n_samples:,}':>20s} "
                          f"{r.evaluations:>14,} {r.ratio:>8.4f} {wall:>8.2f}  {'yes' if same else 'NO'}",
                          flush=True)
        print("twin-pantograph evaluators:", evaluator_costs(twin_one_distance()), flush=True)
        if args.paper_scale:
            paper_scale(args.workers, pool, args.dask)
        if args.large:
            st = build_study(read_study_file(STUDIES / "fivebar_large.toml"))
            for workers in ((1, args.workers) if args.workers > 1 else (1,)):
                t0 = time.perf_counter()
                r = run_study(st, workers=workers, executor=pool if workers > 1 else None)
                wall = time.perf_counter() - t0
                engine = f"{r.engine} ({r.workers}, {r.chunks} chunks)"
                print(f"{'fivebar_large, 10^6 x 10^3':45s} {'culling':12s} {engine:24s} "
                      f"{f'{r.n_designs:,} x {r.n_samples:,}':>20s} {r.evaluations:>14,} {r.ratio:>8.4f} "
                      f"{wall:>8.2f}  (brute force not run: {r.brute_force_evaluations:,} evaluations)", flush=True)
    finally:
        if pool is not None:
            pool.shutdown()
    return 0


def paper_scale(workers: int, pool, dask: bool) -> None:
    """Table VII at full size by culling: evaluations, culled fraction, time and the optimum."""
    st = build_study(read_study_file(STUDIES / "twin_pantograph_table7.toml"))
    client = cluster = None
    if dask:
        from distributed import Client, LocalCluster
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        t0 = time.perf_counter()
        r = run_study(st, workers=workers, executor=pool if workers > 1 else None, client=client, with_report=False)
        wall = time.perf_counter() - t0
    finally:
        if client is not None:
            client.close()
            cluster.close()
    best = r.top()[0]
    culled = r.n_designs - r.exact_designs
    print(f"paper 001 Table VII, {r.n_designs:,} x {r.n_samples:,} ({r.engine}, {r.workers} workers, "
          f"{r.chunks} chunks): {r.evaluations:,} evaluations (ratio {r.ratio:.3g} of brute force's "
          f"{r.brute_force_evaluations:,}), {r.exact_designs:,} exact, culled fraction "
          f"{culled / r.n_designs:.6f}, {wall:.1f} s wall, {r.work_seconds:.1f} s work; optimum "
          + ", ".join(f"{p.name} = {best[p.name]:g} {p.unit}" for p in st.parameters)
          + f": GII {best['value']:.6f}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
