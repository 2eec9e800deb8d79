"""How a study's search runs: chunks of design ids searched exactly, merged into the global top K.

Splitting the design space
--------------------------
``run_study`` cuts the design ids into chunks (``plan_chunks``: a strided warm-up chunk
spread over the whole space, then contiguous pieces) and searches each exactly
(``culling_search`` / ``count_search``), on the calling process, on a
``ProcessPoolExecutor`` or on a ``dask.distributed`` client. A chunk started after others
finished gets their merged K-th best as its ``floor`` and their worst samples as its first
probes; ``merge_top_k`` of all chunks is the global top K, identical to a single-process run
whatever the order chunks finish in (proof in ``metrics.design.culling``). Only the *cost*
depends on the scheduling.
"""
from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .count import count_brute_force, count_search
from .culling import brute_force, culling_search
from .evaluators import evaluator_for, largest_apparent_mass
from .pools import DaskPool, LocalPool, dask_threads
from .ranking import SearchResult, merge_top_k
from .records import Recorder, StudyResult, study_report, to_objective
from .study import METHODS, Study


@dataclass(frozen=True)
class ChunkOutcome:
    result: SearchResult
    records: dict[str, np.ndarray]
    wall: float


def search_chunk(study: Study, design_ids: np.ndarray, *, method: str = "culling", top_k: int | None = None,
                 floor: tuple[float, int] | None = None, initial_samples=None) -> ChunkOutcome:
    """Search one chunk of design ids exactly (the unit of work a worker runs).

    Parameters
    ----------
    study : Study
        One study of a series.
    design_ids : array_like of int, shape (k,)
        The chunk's design ids.
    method : {"culling", "brute_force"}
        The search.
    top_k : int, optional
        Designs to rank (default the study's ``top_k``).
    floor : (float, int), optional
        ``(value, design id)`` from chunks already searched (``SearchResult.kth``).
    initial_samples : array_like of int, optional
        First probes (the merged ``probes`` of earlier chunks).

    Returns
    -------
    ChunkOutcome
        The chunk's ``SearchResult``, per-design records (each (k,)) and wall time in s.
    """
    t0 = time.perf_counter()
    ev = evaluator_for(study)
    k = int(top_k or study.objective.top_k)
    rec = Recorder(ev, np.sort(np.asarray(design_ids, np.int64)), ev.n_samples, ev.form, study.objective.infeasible)
    S = ev.n_samples
    ids = rec.ids
    if ev.form == "sum":
        if method == "brute_force":
            res = count_brute_force(rec, ids, S, top_k=k)
        else:
            res = count_search(rec, ids, S, top_k=k, floor=floor, initial_samples=initial_samples)
    else:
        if method == "brute_force":
            res = brute_force(rec, ids, S, form=ev.form, infeasible=study.objective.infeasible, top_k=k)
        else:
            res = culling_search(rec, ids, S, form=ev.form, infeasible=study.objective.infeasible, top_k=k,
                                 floor=floor, initial_samples=initial_samples)
    records = rec.records()
    # The recorder saw exactly what the search saw: the listed designs' values must agree.
    internal = records["value"] if ev.form != "sum" else -records["value"]
    loc = np.searchsorted(ids, res.top_designs)
    if not (np.all(records["exact"][loc]) and np.array_equal(internal[loc], res.top_values)):
        raise RuntimeError("per-design records disagree with the search result: the evaluator is not "
                           "deterministic (a value depends on which pairs share a call)")
    return ChunkOutcome(res, records, time.perf_counter() - t0)


def plan_chunks(n_designs: int, n_chunks: int, *, warmup: int = 1024) -> list[np.ndarray]:
    """Design ids cut into chunks: a strided *warm-up* chunk spread over the whole design space
    (``min(warmup, n_designs // 8)`` designs), then the rest in ``n_chunks`` contiguous pieces;
    one chunk when ``n_chunks == 1`` and the space is small. The warm-up runs first and alone:
    its K-th best becomes the floor, and its worst samples the probes, of every later chunk,
    which then cull most of their designs on the first probes. Any split gives the same result
    (``merge_top_k``); only the cost changes.

    Parameters
    ----------
    n_designs : int
        ``D``, designs in the study.
    n_chunks : int
        Contiguous pieces after the warm-up.
    warmup : int
        Largest warm-up chunk.

    Returns
    -------
    list of ndarray of int
        The chunks' design ids; together ``0 .. D - 1``, each once.

    Examples
    --------
    >>> [c.tolist() for c in plan_chunks(10, 2)]
    [[5], [0, 1, 2, 3, 4], [6, 7, 8, 9]]
    >>> [c.size for c in plan_chunks(100_000, 4)]
    [1024, 24744, 24744, 24744, 24744]
    """
    ids = np.arange(n_designs, dtype=np.int64)
    size = min(warmup, n_designs // 8)
    if size < 1 or (n_chunks == 1 and n_designs <= 65536):
        return [part for part in np.array_split(ids, n_chunks)]
    stride = n_designs // size
    first = ids[stride // 2::stride][:size]
    mask = np.ones(n_designs, bool)
    mask[first] = False
    rest = ids[mask]
    # Never more pieces than designs left: an empty chunk has nothing to search.
    return [first] + [part for part in np.array_split(rest, min(n_chunks, rest.size)) if part.size]


def default_chunks(n_designs: int, parallel: int) -> int:
    """Chunks to cut a design space into: about 64k designs each, and at least four per worker
    when there are several (so floors from finished chunks reach the later ones).

    Parameters
    ----------
    n_designs : int
        ``D``, designs in the study.
    parallel : int
        Workers (processes or Dask threads).

    Returns
    -------
    int
        Between 1 and ``n_designs``.

    Examples
    --------
    >>> default_chunks(100_000, 1), default_chunks(1000, 4), default_chunks(10, 8)
    (2, 16, 10)
    """
    n = max(1, math.ceil(n_designs / 65536))
    if parallel > 1:
        n = max(n, 4 * parallel)
    return int(min(n, n_designs))


def run_study(study: Study, *, workers: int = 1, client=None, executor=None, chunks: int | None = None,
              method: str = "culling",
              top_k: int | None = None, progress: Callable[[dict], None] | None = None,
              max_probes: int = 32, with_report: bool = True) -> StudyResult:
    """Search ``study`` (one series value; see ``Study.runs``) exactly.

    Parameters
    ----------
    study : Study
        One study of a series (``Study.runs``), from ``build_study``.
    workers : int
        Local worker processes (1: this process, no pool).
    client : dask.distributed.Client, optional
        Chunks run on its cluster (``workers`` unused).
    executor : concurrent.futures.Executor, optional
        An executor of ``workers`` processes to use (and leave open), e.g. ``process_pool(n)``
        shared by the runs of a series; default: one is made.
    chunks : int, optional
        How many chunks to cut the design ids into (default ``default_chunks``).
    method : {"culling", "brute_force"}
        ``"brute_force"``: every design on every sample.
    top_k : int, optional
        Designs to rank (default the study's ``top_k``).
    progress : callable ``(dict) -> None``, optional
        Called with a dict (``chunks_done``, ``chunks``, ``designs_done``, ``designs``,
        ``evaluations``, ``seconds``) after each chunk.
    max_probes : int
        Probes handed from finished chunks to later ones (min and ratio forms).
    with_report : bool
        Answer the study's [report] table too.

    Returns
    -------
    StudyResult
        The top designs in objective units, per-design records (sorted ids) and costs.

    Raises
    ------
    metrics.budget.BudgetError
        When the study would not fit in memory.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if study._runs:
        raise ValueError("run_study takes one study of a series; loop over study.runs()")
    k = int(top_k or study.objective.top_k)
    if k < 1:
        raise ValueError(f"top_k must be a positive integer, got {top_k!r}")
    t0 = time.perf_counter()
    D = study.n_designs
    # Local processes beyond the CPU count, or beyond the designs, only add start-up time.
    parallel = dask_threads(client) if client is not None else max(1, min(int(workers), os.cpu_count() or 1, D))
    n_chunks = int(chunks) if chunks is not None else default_chunks(D, parallel)
    if not 1 <= n_chunks <= D:
        raise ValueError(f"chunks must be between 1 and the {D} designs, got {chunks!r}")
    parts = plan_chunks(D, n_chunks) if chunks is None else np.array_split(np.arange(D, dtype=np.int64), n_chunks)
    n_chunks = len(parts)
    local_ev = evaluator_for(study)
    S = local_ev.n_samples
    from ..budget import check_fits, study_estimate
    check_fits(study_estimate(D, S, len(study.mechanism.task_names), workers=parallel if client is None else 1),
               advice="use a coarser design grid or workspace, or fewer workers")
    if client is not None:
        pool, engine = DaskPool(client), "dask"
    elif parallel > 1 and n_chunks > 1:
        pool, engine = LocalPool(min(parallel, n_chunks), executor), "processes"
    else:
        pool, engine = None, "single process"
    outcomes: list[ChunkOutcome] = []
    done_designs = 0

    def state():
        if not outcomes:
            return None, None
        merged = merge_top_k([o.result for o in outcomes], top_k=k)
        floor = merged.kth if len(merged.top_designs) == k else None
        probes = merged.probes[:max_probes] if study.objective.form != "sum" else merged.probes[:S]
        return floor, (probes if probes.size else None)

    def report(o: ChunkOutcome):
        nonlocal done_designs
        outcomes.append(o)
        done_designs += o.result.n_designs
        if progress is not None:
            progress({"chunks_done": len(outcomes), "chunks": n_chunks, "designs_done": done_designs,
                      "designs": D, "evaluations": sum(x.result.evaluations for x in outcomes),
                      "seconds": time.perf_counter() - t0})

    if pool is None:
        for ids in parts:
            floor, probes = state()
            report(search_chunk(study, ids, method=method, top_k=k, floor=floor, initial_samples=probes))
    else:
        try:
            queue = list(parts)
            running = set()
            slots = min(parallel, n_chunks)
            shared = pool.share(study)
            if len(parts) > 1 and parts[0].size != parts[1].size and chunks is None:
                report(pool.submit(search_chunk, shared, queue.pop(0), method=method, top_k=k).result())
            while queue or running:
                while queue and len(running) < slots:
                    floor, probes = state()
                    running.add(pool.submit(search_chunk, shared, queue.pop(0), method=method, top_k=k,
                                            floor=floor, initial_samples=probes))
                for fut in pool.wait_first(running):
                    running.discard(fut)
                    report(fut.result())
        except BaseException:
            pool.abort()
            raise
        finally:
            pool.close()
    merged = merge_top_k([o.result for o in outcomes], top_k=k)
    keep = merged.top_designs >= 0
    rec = {name: np.concatenate([o.records[name] for o in outcomes]) for name in outcomes[0].records}
    order = np.argsort(rec["design"], kind="stable")
    rec = {name: v[order] for name, v in rec.items()}
    result = StudyResult(
        study=study, method=method, top_designs=merged.top_designs[keep],
        top_values=to_objective(study, merged.top_values[keep]), n_designs=D, n_samples=S,
        evaluations=merged.evaluations, exact_designs=int(rec["exact"].sum()),
        wall_seconds=time.perf_counter() - t0, work_seconds=float(sum(o.wall for o in outcomes)),
        chunks=n_chunks, workers=(parallel if pool is not None else 1), engine=engine, records=rec,
        evaluator_note=local_ev.note)
    if study.objective.uses_mass and result.top_designs.size:
        result = replace(result, top_masses=largest_apparent_mass(study, result.top_designs))
    if with_report and study.report is not None:
        result = replace(result, report=study_report(study, result))
    return result
