"""``isoforce optimize``: run a design study (a TOML file) and rank its designs exactly.

::

    isoforce optimize STUDY [--json] [--top K] [--workers N] [--dask | --scheduler ADDRESS]
                            [--out results.npz|results.csv] [--method culling|brute_force]
    isoforce optimize --list

STUDY is a shipped study key (``--list``) or a path to a ``.toml`` study
(``resources.study_schema`` documents the format). The search is exact: the optimum and the
runners-up are the ones brute force would find, with the same values and tie order
(ties go to the smaller design id, i.e. the earlier grid point). A search that runs longer
than about 2 s shows its progress on stderr (``app.cli._progress``); stdout gets the ranking,
the report of the study's ``[report]`` table, the number of (design, sample) evaluations
against brute force's ``D x S`` (computed, not run), and the wall time.

Every design's record goes to ``--out`` (default ``<study>_results.npz`` in the current
folder), atomically: designs evaluated on the whole workspace with their exact value, culled
designs with the bound the search had when it dropped them (an upper bound of the value for
``min_isotropic_force``, ``min_force_per_apparent_mass`` and ``gii``, a lower bound of the count
for ``count_condition_above``; column ``exact`` tells which) and the samples it came from.

A study with ``max_apparent_mass`` (kg) prints how many designs the bound removed (column
``over_mass_bound`` of the results; under culling, those the search met over the bound: a
design the objective culls first is not looked at further, so ``--method brute_force`` counts
every one) and each listed design's largest apparent mass beside its value; so does a
``min_force_per_apparent_mass`` study (N/kg = m/s^2). A design over the bound has value
``-inf`` (a count: ``inf``): infeasible.

Parallel runs: ``--workers N`` local processes (default: the CPU count for studies big
enough to pay for starting them, else 1), or ``--scheduler ADDRESS`` for a running
``dask.distributed`` scheduler (needs the ``dask`` extra; the scheduler and every worker must
import isoforce too: the scheduler unpickles the tasks), or ``--dask`` for a ``LocalCluster`` of
``--workers`` processes (default the CPU count) started for the run and stopped after it. The
study goes to every worker once (``Client.scatter``). Results are identical to the
single-process run; only the evaluation count depends on the order chunks finish in.

Printed for every run: the evaluations against brute force's ``D x S``, the exactly evaluated
and the culled designs (the culled fraction) and the wall time (``--json``: ``evaluations``,
``culled_fraction``, ``wall_seconds``).
"""
from __future__ import annotations

import argparse
import os
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from app.cli._args import UsageError, int_at_least
from app.cli._format import number, print_json, table
from app.cli._progress import progress_for
from app.files.export import MAP_SUFFIXES, atomic_write, check_output
from metrics.design import (
    BOUND_MEANING,
    METHODS,
    Study,
    StudyResult,
    build_study,
    evaluator_for,
    process_pool,
    run_study,
    stop_process_pool,
)
from resources import list_studies, load_study

#: Studies whose brute-force cost (D x S, weighted by the evaluator's cost) is below this run
#: on one process by default: starting worker processes takes longer than the search.
AUTO_PARALLEL_PAIRS = 5e7


def register(subparsers) -> None:
    """Add the ``optimize`` subcommand; its ``func`` is ``run``."""
    p = subparsers.add_parser(
        "optimize", help="run a design study (TOML) and rank its designs exactly",
        description="Search a study's design grid exactly (culling: the same optimum and runners-up as brute "
                    "force, far fewer evaluations), print the ranking, the evaluations against brute force "
                    "and the wall time, and save every design's record (exact value, or the bound it was "
                    "culled with).")
    p.add_argument("study", metavar="STUDY", nargs="?", help="shipped study key (see --list) or path to a .toml")
    p.add_argument("--list", action="store_true", help="list the shipped studies and exit")
    p.add_argument("--top", type=_positive_int, metavar="K",
                   help="rank the K best designs (default: the study's top_k)")
    p.add_argument("--workers", type=_positive_int, metavar="N",
                   help="local worker processes (default: CPU count for large studies, else 1)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on a dask.distributed scheduler, e.g. tcp://host:8786")
    p.add_argument("--dask", action="store_true",
                   help="run on a dask.distributed LocalCluster of --workers processes (default: the CPU count)")
    p.add_argument("--out", metavar="FILE", help="results file, .npz or .csv (default: <study>_results.npz)")
    p.add_argument("--method", choices=METHODS, default="culling",
                   help="culling (default) or brute_force (every design on every sample, to check)")
    p.add_argument("--chunks", type=_positive_int, metavar="N", help=argparse.SUPPRESS)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


_positive_int = int_at_least(1)


def shipped_studies() -> list[str]:
    """Keys of the studies in ``resources/studies``, sorted (``resources.list_studies``)."""
    return list_studies()


def study_named(name: str) -> Study:
    """A shipped study by key, or a study file by path, ready to search; ``UsageError`` naming STUDY."""
    try:
        return build_study(load_study(name))
    except ValueError as exc:       # resources.StudyError, or a design the model refuses
        raise UsageError(f"STUDY: {exc}") from None


def _designs_done(callback):
    """``run_study``'s progress (a dict after each chunk) as a share of ``callback``'s part (None: none)."""
    if callback is None:
        return None
    return lambda info: callback(info["designs_done"] / max(1, info["designs"]))


def auto_workers(study: Study) -> int:
    """1 for studies small enough that starting processes costs more than it saves."""
    runs = study.runs()
    ev = evaluator_for(runs[0])
    pairs = sum(r.n_designs for r in runs) * ev.n_samples * ev.relative_cost
    return (os.cpu_count() or 1) if pairs > AUTO_PARALLEL_PAIRS else 1


def run(args: argparse.Namespace) -> int:
    if args.list:
        rows = [("key", "designs", "samples", "objective", "name")]
        for key in shipped_studies():
            s = study_named(key)
            run0 = s.runs()[0]
            series = f" x {len(s.series.values)} runs" if s.series is not None else ""
            rows.append((key, f"{run0.n_designs:,}{series}", f"{run0.n_samples:,}", s.objective.kind, s.name))
        if args.json:
            print_json({"studies": [dict(zip(rows[0], r)) for r in rows[1:]]})
        else:
            print(table(rows))
        return 0
    if args.study is None:
        raise UsageError("STUDY is needed (a shipped study key, see --list, or a path to a .toml)")
    if args.scheduler is not None and args.workers is not None:
        raise UsageError("--scheduler and --workers cannot be combined: the cluster decides the workers")
    if args.scheduler is not None and args.dask:
        raise UsageError("--dask and --scheduler cannot be combined: --dask starts a local cluster, "
                         "--scheduler connects to a running one")
    study = study_named(args.study)
    out = Path(args.out) if args.out is not None else Path(f"{study.key}_results.npz")
    try:
        check_output(out, MAP_SUFFIXES, "--out")      # before the search, not after it
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    top_k = args.top or study.objective.top_k
    client = executor = cluster = None
    if args.scheduler is not None:
        client = _dask_client(args.scheduler)
        workers = None
    elif args.dask:
        cluster, client = _local_cluster(args.workers or os.cpu_count() or 1)
        workers = None
    else:
        workers = args.workers or auto_workers(study)
        if workers > 1:
            executor = process_pool(workers)
    t0 = time.perf_counter()
    results: list[StudyResult] = []
    runs = study.runs()
    designs = sum(sub.n_designs for sub in runs)
    try:
        # Not predicted: the bar shows once the search has run PROGRESS_AFTER seconds.
        with progress_for("isoforce optimize", None, designs, unit="designs", json_out=args.json) as progress:
            done = 0
            for sub in runs:
                if sub.series_value is not None:
                    progress.step(f"{sub.series.key} = {sub.series_value:g}")
                results.append(run_study(sub, workers=workers or 1, client=client, executor=executor, top_k=top_k,
                                         method=args.method, chunks=args.chunks,
                                         progress=_designs_done(progress.part(done, sub.n_designs))))
                done += sub.n_designs
    except (KeyboardInterrupt, MemoryError):
        if executor is not None:        # stop the worker processes now, not after their chunks
            stop_process_pool(executor)
            executor = None
        raise
    except RuntimeError as exc:
        if client is None:
            raise
        # e.g. "Error during deserialization of the task graph": the scheduler or a worker
        # cannot import isoforce.
        option = "--dask" if args.dask else "--scheduler"
        raise UsageError(f"{option}: the cluster could not run the study ({' '.join(str(exc).split())}); "
                         f"the scheduler and every worker need isoforce importable (pip install "
                         f"'isoforce[dask]' in their environment)") from None
    finally:
        if executor is not None:
            executor.shutdown(wait=True, cancel_futures=True)
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    wall = time.perf_counter() - t0
    target = write_results(results, out)
    summary = study_summary(study, results, wall, target)
    if args.json:
        print_json(summary)
    else:
        print(format_summary(study, results, wall, target))
    return 0


def _local_cluster(workers: int):
    """A ``LocalCluster`` of ``workers`` single-threaded processes and its client (no dashboard)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise UsageError(f"--dask needs dask.distributed (pip install 'isoforce[dask]'): {exc}") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        return cluster, Client(cluster)
    except BaseException:
        cluster.close()
        raise


def _dask_client(address: str):
    try:
        from distributed import Client
    except ImportError as exc:
        raise UsageError(f"--scheduler needs dask.distributed (pip install 'isoforce[dask]'): {exc}") from None
    try:
        return Client(address, timeout="10s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise UsageError(f"--scheduler: cannot connect to {address!r}: {exc}") from None


# -- output -------------------------------------------------------------------------------------
def _units(study: Study) -> dict[str, str]:
    return {p.name: p.unit for p in study.parameters}


def _design_text(study: Study, row: dict) -> str:
    units = _units(study)
    return ", ".join(f"{n} = {number(row[n])}{(' ' + units[n]) if units[n] else ''}" for n in units)


def _value_text(study: Study, value: float) -> str:
    unit = study.objective.unit
    if study.objective.kind == "count_condition_above" and np.isfinite(value):
        return f"{int(value)} {unit}"
    if study.objective.max_apparent_mass is not None and abs(value) == np.inf \
            and (value < 0) == (study.objective.form != "sum"):
        return f"{number(value)} (infeasible: unreachable or over the apparent-mass bound)"
    return f"{number(value)}{(' ' + unit) if unit else ''}"


def run_summary(result: StudyResult) -> dict[str, Any]:
    """One run (series value) as a JSON-ready dict."""
    study = result.study
    top = result.top()
    entry: dict[str, Any] = {
        "series_value": study.series_value,
        "optimum": top[0] if top else None,
        "top": top,
        "evaluations": result.evaluations,
        "brute_force_evaluations": result.brute_force_evaluations,
        "ratio": result.ratio,
        "designs": result.n_designs,
        "samples": result.n_samples,
        "exact_designs": result.exact_designs,
        "culled_designs": result.n_designs - result.exact_designs,
        "culled_fraction": (result.n_designs - result.exact_designs) / max(1, result.n_designs),
        "wall_seconds": result.wall_seconds,
        "work_seconds": result.work_seconds,
        "chunks": result.chunks,
        "workers": result.workers,
        "engine": result.engine,
        "evaluator": result.evaluator_note,
    }
    if study.objective.max_apparent_mass is not None:
        entry["over_mass_bound"] = result.over_bound
    if study.series is not None and study.series.paper is not None:
        entry["paper"] = study.series.paper[study.series.values.index(study.series_value)]
    if result.report is not None:
        r = result.report
        entry["report"] = {"reference": r.reference, "reference_value": r.reference_value, "tolerance": r.tolerance,
                           "target": r.target, "smallest_parameter": r.smallest, "smallest": r.smallest_design,
                           "smallest_value": r.smallest_value, "checks": r.checks, "evaluations": r.evaluations}
    return entry


def study_summary(study: Study, results: list[StudyResult], wall: float, target: Path) -> dict[str, Any]:
    obj = study.objective
    return {
        "study": study.key, "name": study.name, "description": study.description, "source": study.source,
        "mechanism": study.kind,
        "objective": {"kind": obj.kind, "direction": obj.direction, "unit": obj.unit, "threshold": obj.threshold,
                      "infeasible": obj.infeasible, "S_T": obj.s_t, "frame": obj.frame if obj.kind == "gii" else None,
                      "max_apparent_mass": obj.max_apparent_mass},
        "parameters": [{"name": p.name, "unit": p.unit, "count": p.size, "min": min(p.display), "max": max(p.display)}
                       for p in study.parameters],
        "workspace": study.runs()[0].workspace.description,
        "series": None if study.series is None else {"key": study.series.key, "unit": study.series.unit,
                                                     "values": study.series.values, "paper": study.series.paper},
        "runs": [run_summary(r) for r in results],
        "evaluations": sum(r.evaluations for r in results),
        "brute_force_evaluations": sum(r.brute_force_evaluations for r in results),
        "ratio": sum(r.evaluations for r in results) / max(1, sum(r.brute_force_evaluations for r in results)),
        "wall_seconds": wall,
        "results_file": str(target),
        "culled_value_means": BOUND_MEANING[obj.kind],
    }


def format_summary(study: Study, results: list[StudyResult], wall: float, target: Path) -> str:
    obj = study.objective
    first = results[0]
    lines = [f"{study.name}  [{study.source}]"]
    if study.description:
        lines.append(f"  {study.description}")
    grid = " x ".join(f"{p.name} {p.size}" for p in study.parameters)
    lines.append(f"  designs: {first.n_designs:,} ({grid}); samples: {first.n_samples:,} "
                 f"({study.runs()[0].workspace.description})")
    if obj.kind == "min_isotropic_force":
        what = "global minimum isotropic force (maximise)"
    elif obj.kind == "gii":
        what = f"Global Isotropy Index, S_T = {list(obj.s_t or ())}, {obj.frame} frame (maximise)"
    elif obj.kind == "sensor_gii":
        s_t = "the hand's velocities (paper 001 eq. 27)" if obj.s_t is None else list(obj.s_t)
        what = f"sensor-resolution GII (paper 001 eqs. 23-27), S_T = {s_t}, {obj.frame} frame (maximise)"
    elif obj.kind == "min_force_per_apparent_mass":
        what = ("global minimum of isotropic force / largest apparent mass, N/kg = m/s^2 (maximise)")
    else:
        what = f"count of samples with condition number > {obj.threshold:g} (minimise)"
    lines.append(f"  objective: {what}" + ("" if obj.kind == "count_condition_above"
                                                       else f"; infeasible samples: {obj.infeasible}"))
    if obj.max_apparent_mass is not None:
        lines.append(f"  bound: largest apparent mass <= {number(obj.max_apparent_mass)} kg at every sample "
                     f"(a design over it is infeasible)")
    lines.append(f"  engine: {first.engine}, {first.workers} worker(s), {first.chunks} chunk(s); "
                 f"evaluator: {first.evaluator_note}")
    for res in results:
        lines.append("")
        lines += _format_run(study, res)
    if study.series is not None:
        lines.append("")
        lines.append(f"{study.series.key} ({study.series.unit}) against the optimum:")
        head = [study.series.key.split(".")[-1]] + [p.name for p in study.parameters] + ["value"]
        if study.series.paper is not None:
            head.append("paper")
        head += ["evaluations / D x S", "s"]
        rows = [head]
        for i, res in enumerate(results):
            top = res.top()
            row = [number(res.study.series_value)]
            row += [number(top[0][p.name]) if top else "-" for p in study.parameters]
            row.append(number(top[0]["value"], 4) if top else "-")
            if study.series.paper is not None:
                row.append(number(study.series.paper[i]))
            row += [f"{res.ratio:.4f}", f"{res.wall_seconds:.1f}"]
            rows.append(row)
        lines.append(table(rows, "  "))
    total_e = sum(r.evaluations for r in results)
    total_b = sum(r.brute_force_evaluations for r in results)
    if len(results) > 1:
        lines.append(f"all runs: {total_e:,} evaluations of brute force's {total_b:,}: ratio {total_e / total_b:.4g}")
    lines.append(f"wall time: {wall:.2f} s")
    n = sum(r.n_designs for r in results)
    lines.append(f"wrote {target} ({n:,} designs: exact value where exact = 1, else the "
                 f"{BOUND_MEANING[obj.kind]})")
    return "\n".join(lines)


def _format_run(study: Study, res: StudyResult) -> list[str]:
    lines = []
    sub = res.study
    if sub.series_value is not None:
        lines.append(f"{sub.series.key} = {number(sub.series_value)} {sub.series.unit}")
    top = res.top()
    if not top:
        lines.append("  no design found")
        return lines
    best = top[0]
    if not np.isfinite(best["value"]) and best["value"] < 0:
        # Every design ties at -inf: there is no optimum to name and no ranking to print.
        lines.append("  no design is feasible on the whole workspace (every value is -inf): no optimum")
    else:
        mass = f"; largest apparent mass {number(best['max_apparent_mass'], 6)} kg" if "max_apparent_mass" in best \
            else ""
        lines.append(f"  optimum: {_design_text(study, best)}: {_value_text(study, best['value'])}{mass}")
        units = _units(study)
        head = ["rank"] + [f"{n} ({u})" if u else n for n, u in units.items()] + [
            f"value ({study.objective.unit})" if study.objective.unit else "value"]
        if mass:
            head.append("max apparent mass (kg)")
        rows = [head] + [[str(r["rank"])] + [number(r[n]) for n in units] + [number(r["value"], 8)]
                         + ([number(r["max_apparent_mass"], 6)] if mass else []) for r in top]
        lines.append(table(rows, "  "))
    fewer = 1.0 / res.ratio if res.ratio > 0 else float("inf")
    lines.append(f"  evaluations: {res.evaluations:,} of brute force's {res.brute_force_evaluations:,} "
                 f"(D x S = {res.n_designs:,} x {res.n_samples:,}): ratio {res.ratio:.4g} ({fewer:.1f}x fewer)")
    culled = res.n_designs - res.exact_designs
    lines.append(f"  exactly evaluated designs: {res.exact_designs:,} of {res.n_designs:,}; culled {culled:,} "
                 f"(culled fraction {culled / max(1, res.n_designs):.6f}); "
                 f"time {res.wall_seconds:.2f} s wall, {res.work_seconds:.2f} s work")
    bound = study.objective.max_apparent_mass
    if bound is not None:
        how = "every one" if res.method == "brute_force" else "those the search met over it; brute_force counts all"
        lines.append(f"  apparent-mass bound {number(bound)} kg: removed {res.over_bound:,} of {res.n_designs:,} "
                     f"designs ({how})")
    if res.report is not None:
        lines += _format_report(study, res)
    return lines


def _format_report(study: Study, res: StudyResult) -> list[str]:
    r = res.report
    lines = ["  report:"]
    if r.reference is not None:
        lines.append(f"    reference ({_design_text(study, r.reference)}): {_value_text(study, r.reference_value)}; "
                     f"within {r.tolerance:g} (relative): {_value_text(study, r.target)}")
    if r.smallest is not None:
        if r.smallest_design is None:
            lines.append(f"    no grid design reaches it: the smallest {r.smallest} does not exist on this grid")
        else:
            lines.append(f"    smallest {r.smallest} reaching it: {number(r.smallest_design[r.smallest])} "
                         f"({_design_text(study, r.smallest_design)}: {_value_text(study, r.smallest_value)})")
    for c in r.checks:
        rel = c.get("vs_reference")
        rel_text = "" if rel is None else f" ({100 * rel:+.2f} % vs reference)"
        reach = "" if "reaches" not in c else ("; reaches it" if c["reaches"] else "; does NOT reach it")
        lines.append(f"    {c['label']}: {_value_text(study, c['value'])}{rel_text}{reach}")
    lines.append(f"    ({r.evaluations:,} evaluations for the report)")
    return lines


def results_columns(results: list[StudyResult]) -> tuple[list[str], list[np.ndarray]]:
    """Column names and arrays of the results file (all runs stacked)."""
    study = results[0].study
    names: list[str] = []
    cols: dict[str, list[np.ndarray]] = {}

    def add(name, arr):
        if name not in cols:
            names.append(name)
            cols[name] = []
        cols[name].append(np.asarray(arr))

    for res in results:
        rec = res.records
        if res.study.series is not None:
            add(res.study.series.key.split(".")[-1] + "_series", np.full(rec["design"].size, res.study.series_value))
        add("design", rec["design"])
        for p, values in res.study.design_display(rec["design"]).items():
            add(p, values)
        add("value", rec["value"])
        add("exact", rec["exact"])
        add("samples_evaluated", rec["samples"])
        if res.study.objective.max_apparent_mass is not None:
            add("over_mass_bound", rec["over_bound"])
    del study
    return names, [np.concatenate(cols[n]) for n in names]


#: Deflate level of the results file. Table VII's 22 M designs (1.43 GB of arrays), three runs
#: each: level 1 wrote 181.5 MB in 7.2 to 7.9 s of CPU, numpy's ``savez_compressed`` (level 6)
#: 175.2 MB in 23.0 to 24.1 s, ``savez`` (stored) 1.43 GB in 3.2 to 4.3 s (docs/paper_scale.md).
NPZ_LEVEL = 1


def write_npz(fh, arrays: dict[str, np.ndarray]) -> None:
    """``np.savez_compressed(fh, **arrays)`` at deflate level ``NPZ_LEVEL``: the same ``.npz``
    layout (one ``NAME.npy`` member per array, read by ``np.load``), written 3 times faster.

    Parameters
    ----------
    fh : binary file object, open for writing
    arrays : dict of str to ndarray
        Names and arrays (no object arrays).
    """
    with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=NPZ_LEVEL,
                         allowZip64=True) as zf:
        for name, arr in arrays.items():
            with zf.open(name + ".npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(arr), allow_pickle=False)


def write_results(results: list[StudyResult], path: Path) -> Path:
    """Every design's record, atomically: ``.npz`` (arrays + metadata) or ``.csv``."""
    names, arrays = results_columns(results)
    study = results[0].study
    if path.suffix.lower() == ".npz":
        meta = {"objective": np.array(study.objective.kind), "value_unit": np.array(study.objective.unit),
                "culled_value_means": np.array(BOUND_MEANING[study.objective.kind]),
                "parameters": np.array([p.name for p in study.parameters]),
                "parameter_units": np.array([p.unit for p in study.parameters]),
                "columns": np.array(names)}

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as fh:
                write_npz(fh, {**dict(zip(names, arrays)), **meta})

        return atomic_write(path, write, name="--out")

    def write_csv(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(f"# {study.name}: objective {study.objective.kind} ({study.objective.unit or 'no unit'}); "
                     f"value = exact where exact = 1, else the {BOUND_MEANING[study.objective.kind]}\n")
            fh.write(",".join(names) + "\n")
            formats = []
            for arr in arrays:
                formats.append("%d" if arr.dtype.kind in "biu" else "%.17g")
            table = np.column_stack([a.astype(np.int64) if a.dtype == bool else a for a in arrays])
            np.savetxt(fh, table, fmt=formats, delimiter=",")

    return atomic_write(path, write_csv, name="--out")
