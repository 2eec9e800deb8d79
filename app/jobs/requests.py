"""What the app runs in the background: immutable requests and the jobs that answer them.

Built on the GUI thread from the model, run by ``app.jobs.runner.JobRunner`` on its worker thread.
Plain Python, no Qt: tested with ``tests/app/test_jobs.py``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

from app.jobs import heap, map_worker
from app.logic.colour_limits import map_colour_limits
from kinematics.contract import Mechanism
from metrics.budget import check_map
from metrics.design import Study, StudyResult, run_study
from metrics.loading import DEFAULT_LOADING, Loading
from metrics.workspace import Cancelled, GridSpec, WorkspaceMap, compute_map

#: The scheduler's tag of the current design's coarse maps: their own, so the refinement (tag
#: ``"current"``) never cancels a coarse map before it is shown; a newer coarse map does.
COARSE_TAG = "current-coarse"
#: The scheduler's tag of a map computed only to time it, never shown: a dragged slider's full map,
#: timed while the design rests (``MainWindow._probe_drag_rate``).
PROBE_TAG = "drag-rate"


@dataclass(frozen=True)
class MapRequest:
    """An immutable description of one map to compute."""

    mechanism: Mechanism
    grid: GridSpec
    quantities: tuple[str, ...]
    stage: str = "full"          # "coarse" while a slider moves, "full" when it stops
    tag: str = "current"         # "current" or "reference" (a pinned design)
    loading: Loading = DEFAULT_LOADING   # torque rating and gravity (``metrics.loading``)
    generation: int = field(default=-1, compare=False)
    #: The quantity the map view colours (its colour limits are worked out with the map); None: none.
    shown: str | None = field(default=None, compare=False)
    #: A dragged slider's map (the next step follows within tens of ms): no work the drag does not
    #: show (``run_map_for_view``: the heap is handed back at rest, by the map of the released slider).
    drag: bool = field(default=False, compare=False)
    #: Which statistics the map takes (``compute_map(figures=...)``): ``"extremes"`` for a dragged
    #: slider's full map that the statistics' map at rest follows (its legend's figures alone).
    figures: str = field(default="all", compare=False)
    #: When it was asked for (``time.perf_counter``), or None: how long a step waited for it.
    sent_at: float | None = field(default=None, compare=False)

    @property
    def slot(self) -> str:
        """Which map the result fills: ``"current"`` (coarse or full) or ``"reference"``."""
        return "current" if self.tag == COARSE_TAG else self.tag


def run_map(request: MapRequest, progress: Callable[[float], None], cancelled: Callable[[], bool]) -> WorkspaceMap:
    """The map job: ``compute_map`` of the request."""
    # A map that cannot fit in memory is refused before it starts (a BudgetError, delivered
    # to the GUI as the reason the map could not be computed), instead of a MemoryError later.
    check_map(request.mechanism, request.grid.resolution, request.quantities, option="the map's resolution")
    # A coarse map (a slider moving) runs on one core, leaving the other to the GUI thread,
    # which draws the pose glyphs of the same change meanwhile: in the map worker process when
    # it is ready (no turns taken with the GUI thread's Python for the interpreter lock), else here.
    if request.stage == "coarse":
        wmap = map_worker.shared().compute(request.mechanism, request.grid, request.quantities, request.loading)
        if wmap is not None:
            return wmap
    return compute_map(request.mechanism, request.grid, request.quantities, progress=progress, cancelled=cancelled,
                       threads=request.stage != "coarse", loading=request.loading, figures=request.figures)


@dataclass(frozen=True)
class MapResult:
    """What the map job returns: the map and everything the views need of it, computed on the
    worker thread, so the GUI thread only shows it and no view keeps a side cache.

    ``map.errors`` carries the statistics' resolution errors (``compute_map`` accumulates them);
    ``colour_limits`` the ``(lo, hi, capped)`` of the quantity the map view showed when the
    map was asked for (``MapRequest.shown``; p1 and p99 of every feasible value: 1.7 ms for
    the Inverse3's 1000 x 1000 map), empty when it shows none or a quantity drawn without limits.
    """

    map: WorkspaceMap
    colour_limits: dict[str, tuple[float, float, bool]] = field(default_factory=dict)
    #: The job's wall time, s (the map, in the worker process for a coarse one, and its colour
    #: limits): what a slider step waits for, where ``map.seconds`` is ``compute_map``'s alone.
    #: None: not timed (``map.seconds`` then).
    seconds: float | None = None


def run_map_for_view(request: MapRequest, progress: Callable[[float], None],
                     cancelled: Callable[[], bool]) -> MapResult:
    """The app's map job: ``run_map``, then, still on the worker thread, the colour limits of the
    quantity the map view shows. A full map at rest, done or stopped, hands the memory its
    temporaries took back to the system (``app.jobs.heap``: ~10 ms), after its time was taken; a
    dragged slider's (``drag``) leaves that to the map of the released slider: its next step's map
    reuses the memory anyway. A map timed at rest (``PROBE_TAG``) is at rest: it hands it back."""
    start = time.perf_counter()
    try:
        wmap = run_map(request, progress, cancelled)
        limits = map_colour_limits(wmap, request.shown) if request.shown is not None else None
        return MapResult(wmap, {} if limits is None else {request.shown: limits}, time.perf_counter() - start)
    finally:
        if request.stage == "full" and (not request.drag or request.tag == PROBE_TAG):
            heap.release()


@dataclass(frozen=True)
class StudyRequest:
    """A design study to run in-process (chunks in sequence), keeping its ``top_k`` best designs."""

    study: Study
    top_k: int = 10
    tag: str = "study"
    generation: int = field(default=-1, compare=False)


def run_study_job(request: StudyRequest, progress: Callable[[float], None],
                  cancelled: Callable[[], bool]) -> list[StudyResult]:
    """The study job: one ``run_study`` per run of the study (one per series value, else one).

    Cancellation is checked after each chunk (``Cancelled`` raised from ``run_study``'s
    progress callback); progress is the fraction of the whole job done: runs finished plus the
    current run's fraction of designs searched, over the number of runs (one bar for a series).
    """
    def report(info: dict[str, Any]) -> None:
        if cancelled():
            raise Cancelled()
        progress((len(results) + info["designs_done"] / max(1, info["designs"])) / len(runs))

    study = request.study
    runs = study.runs() if study.series is not None else [study]
    results: list[StudyResult] = []
    for run in runs:
        results.append(run_study(run, workers=1, top_k=request.top_k, progress=report))
    return results
