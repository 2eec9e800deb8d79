"""``app.jobs.runner.JobRunner`` without Qt: newest wins, cancellation, stale results dropped.

The fake jobs are driven by events, so every interleaving here is forced, not timed: a job
that "runs" is blocked on a gate the test opens. The last tests run the real ``compute_map``
job. A fresh interpreter checks that the scheduler imports no Qt.
"""
from __future__ import annotations

import dataclasses
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from app.jobs.requests import MapRequest, StudyRequest, run_map, run_study_job
from app.jobs.runner import JobRunner
from metrics.workspace import Cancelled, compute_map
from resources import load_preset

ROOT = Path(__file__).resolve().parents[2]
WAIT = 10.0       # seconds: a hang guard for events, never a timing assertion


class Recorder:
    """``deliver`` and ``progress`` callbacks that remember what arrived, from any thread."""

    def __init__(self) -> None:
        self.delivered: list[tuple[MapRequest, object]] = []
        self.progress: list[tuple[MapRequest, float]] = []
        self.lock = threading.Lock()

    def deliver(self, request, result) -> None:
        with self.lock:
            self.delivered.append((request, result))

    def on_progress(self, request, fraction) -> None:
        with self.lock:
            self.progress.append((request, fraction))

    def labels(self) -> list:
        return [r.mechanism for r, _ in self.delivered]


class GatedJobs:
    """A fake map job per request label (its ``mechanism``): runs ``steps`` chunks.

    Before its first chunk a job reports that it started and waits for its gate. Between
    chunks it checks the cancel flag (unless ``cooperative`` is false) and reports progress.
    It returns ``"map of <label>"`` or raises what ``fail`` maps its label to.
    """

    def __init__(self, steps: int = 4, cooperative: bool = True) -> None:
        self.steps = steps
        self.cooperative = cooperative
        self.gates: dict[str, threading.Event] = {}
        self.started: dict[str, threading.Event] = {}
        self.ran: list[str] = []
        self.chunks: dict[str, int] = {}
        self.cancelled: list[str] = []
        self.fail: dict[str, Exception] = {}
        self.before_chunk: dict[tuple[str, int], callable] = {}

    def gate(self, label: str, open_: bool = False) -> threading.Event:
        self.gates.setdefault(label, threading.Event())
        self.started.setdefault(label, threading.Event())
        if open_:
            self.gates[label].set()
        return self.gates[label]

    def __call__(self, request, progress, cancelled):
        label = request.mechanism
        self.ran.append(label)
        self.gate(label)
        self.started[label].set()
        assert self.gates[label].wait(WAIT), f"gate of {label} never opened"
        if label in self.fail:
            raise self.fail[label]
        for k in range(self.steps):
            hook = self.before_chunk.get((label, k))
            if hook is not None:
                hook()
            if self.cooperative and cancelled():
                self.cancelled.append(label)
                raise Cancelled()
            self.chunks[label] = k + 1
            progress((k + 1) / self.steps)
        return f"map of {label}"


def wait_for(condition, timeout: float = WAIT) -> bool:
    """Poll ``condition`` until true (for state that has no event to wait on)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.001)
    return False


def request(label: str, tag: str = "current", stage: str = "full") -> MapRequest:
    # The scheduler never looks inside a request: a label stands in for mechanism and grid.
    return MapRequest(mechanism=label, grid=None, quantities=("isotropic_force",), stage=stage, tag=tag)


@pytest.fixture
def rec():
    return Recorder()


@pytest.fixture
def jobs():
    return GatedJobs()


@pytest.fixture
def scheduler(rec, jobs):
    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=jobs)
    yield s
    for gate in jobs.gates.values():     # never leave a worker blocked at teardown
        gate.set()
    s.shutdown()


def test_a_request_is_numbered_run_and_delivered_once(scheduler, rec, jobs):
    jobs.gate("a", open_=True)
    a = scheduler.submit(request("a"))
    assert a.generation > 0
    assert scheduler.wait_idle(WAIT)
    assert rec.delivered == [(a, "map of a")]
    assert rec.delivered[0][0].generation == a.generation
    assert scheduler.is_current(a)
    assert [f for _, f in rec.progress] == [0.25, 0.5, 0.75, 1.0]


def test_generations_increase_and_do_not_take_part_in_equality(scheduler, jobs):
    for label in "ab":
        jobs.gate(label, open_=True)
    a1 = scheduler.submit(request("a"))
    a2 = scheduler.submit(request("a"))
    b = scheduler.submit(request("b", tag="reference"))
    assert a1.generation < a2.generation < b.generation
    # Same content, different generation: equal as a description (main window compares mechanisms).
    assert a1 == a2 and a1.generation != a2.generation


def test_newest_wins_the_running_job_is_cancelled_and_queued_ones_never_run(scheduler, rec, jobs):
    jobs.gate("a")
    a = scheduler.submit(request("a"))
    assert jobs.started["a"].wait(WAIT)
    b = scheduler.submit(request("b"))
    jobs.gate("c", open_=True)
    c = scheduler.submit(request("c"))
    assert not scheduler.is_current(a) and not scheduler.is_current(b) and scheduler.is_current(c)
    jobs.gates["a"].set()
    assert scheduler.wait_idle(WAIT)
    assert jobs.ran == ["a", "c"]                 # b was superseded before it started
    assert jobs.cancelled == ["a"]
    assert jobs.chunks.get("a", 0) == 0           # cancelled at its first chunk boundary
    assert rec.delivered == [(c, "map of c")]


def test_a_job_is_cancelled_between_chunks_not_only_before_it_starts(scheduler, rec, jobs):
    jobs.gate("a", open_=True)
    jobs.gate("b", open_=True)
    # A newer request arrives while "a" is between its second and third chunk.
    jobs.before_chunk[("a", 2)] = lambda: scheduler.submit(request("b"))
    scheduler.submit(request("a"))
    assert scheduler.wait_idle(WAIT)
    assert jobs.chunks["a"] == 2 and jobs.cancelled == ["a"]
    assert rec.labels() == ["b"]


def test_a_stale_result_is_dropped_even_when_its_job_ignores_the_cancel_flag(rec):
    jobs = GatedJobs(cooperative=False)
    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=jobs)
    try:
        jobs.gate("a")
        s.submit(request("a"))
        assert jobs.started["a"].wait(WAIT)
        jobs.gate("b", open_=True)
        b = s.submit(request("b"))
        jobs.gates["a"].set()
        assert s.wait_idle(WAIT)
        assert jobs.ran == ["a", "b"] and jobs.chunks["a"] == jobs.steps    # "a" ran to the end...
        assert rec.delivered == [(b, "map of b")]                          # ...and was not delivered
        assert all(r.generation == b.generation for r, _ in rec.progress)  # nor its progress
    finally:
        s.shutdown()


def test_progress_is_reported_only_while_the_request_is_the_newest(scheduler, rec, jobs):
    jobs.gate("a", open_=True)
    jobs.gate("b", open_=True)
    jobs.before_chunk[("a", 2)] = lambda: scheduler.submit(request("b"))
    a = scheduler.submit(request("a"))
    assert scheduler.wait_idle(WAIT)
    a_progress = [f for r, f in rec.progress if r.generation == a.generation]
    b_progress = [f for r, f in rec.progress if r.generation != a.generation]
    assert a_progress == [0.25, 0.5]
    assert b_progress == [0.25, 0.5, 0.75, 1.0]


def test_tags_are_independent_a_newer_current_map_does_not_cancel_the_reference(scheduler, rec, jobs):
    jobs.gate("ref")
    ref = scheduler.submit(request("ref", tag="reference"))
    assert jobs.started["ref"].wait(WAIT)
    jobs.gate("a", open_=True)
    jobs.gate("b", open_=True)
    scheduler.submit(request("a"))
    b = scheduler.submit(request("b"))
    jobs.gates["ref"].set()
    assert scheduler.wait_idle(WAIT)
    assert sorted(rec.labels()) == ["b", "ref"]
    assert scheduler.is_current(ref) and scheduler.is_current(b)


def test_a_failing_job_delivers_its_exception(scheduler, rec, jobs):
    jobs.gate("bad", open_=True)
    jobs.fail["bad"] = ValueError("boom")
    bad = scheduler.submit(request("bad"))
    assert scheduler.wait_idle(WAIT)
    assert len(rec.delivered) == 1
    got_request, result = rec.delivered[0]
    assert got_request == bad and isinstance(result, ValueError) and str(result) == "boom"


def test_cancel_drops_the_running_request_of_a_tag_only(scheduler, rec, jobs):
    jobs.gate("a")
    jobs.gate("ref", open_=True)
    a = scheduler.submit(request("a"))
    assert jobs.started["a"].wait(WAIT)
    ref = scheduler.submit(request("ref", tag="reference"))
    scheduler.cancel("current")
    assert not scheduler.is_current(a) and scheduler.is_current(ref)
    jobs.gates["a"].set()
    assert scheduler.wait_idle(WAIT)
    assert rec.labels() == ["ref"]


def test_shutdown_cancels_the_running_job_and_returns(rec, jobs):
    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=jobs)
    jobs.gate("a")
    a = s.submit(request("a"))
    assert jobs.started["a"].wait(WAIT)
    done = threading.Event()

    def close():
        s.shutdown()
        done.set()

    closer = threading.Thread(target=close)
    closer.start()
    # Only once shutdown has cancelled "a" does the job resume: it must then see the flag.
    assert wait_for(lambda: not s.is_current(a))
    jobs.gates["a"].set()
    assert done.wait(WAIT)
    closer.join(WAIT)
    assert jobs.cancelled == ["a"] and rec.delivered == []


def test_cancel_is_reported_for_the_users_cancel_only_not_for_a_newer_request_or_shutdown(rec):
    jobs, stopped = GatedJobs(), []
    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=jobs, cancelled=stopped.append)
    try:
        jobs.gate("a")
        a = s.submit(request("a"))
        assert jobs.started["a"].wait(WAIT)
        jobs.gate("b")
        b = s.submit(request("b"))          # supersedes "a": no cancellation to report
        jobs.gates["a"].set()
        assert jobs.started["b"].wait(WAIT)
        s.cancel("current")                 # the user stops "b" while it runs
        jobs.gates["b"].set()
        assert s.wait_idle(WAIT)
        assert stopped == [b] and jobs.cancelled == ["a", "b"] and rec.delivered == []
        jobs.gate("c")
        c = s.submit(request("c"))
        assert jobs.started["c"].wait(WAIT)
        jobs.gate("d", open_=True)
        queued = s.submit(request("d", tag="reference"))
        s.cancel("reference")               # cancelled before it started: reported too
        jobs.gates["c"].set()
        assert s.wait_idle(WAIT)
        assert stopped == [b, queued] and rec.delivered == [(c, "map of c")]
        assert a not in stopped
    finally:
        s.shutdown()
    jobs.gate("e")
    s2 = JobRunner(deliver=rec.deliver, job=jobs, cancelled=stopped.append)
    s2.submit(request("e"))
    assert jobs.started["e"].wait(WAIT)
    closer = threading.Thread(target=s2.shutdown)
    closer.start()
    jobs.gates["e"].set()
    closer.join(WAIT)
    assert stopped == [b, queued]           # shutdown reports nothing


def test_a_cancelled_job_that_ignores_the_flag_is_reported_cancelled_not_delivered(rec):
    jobs, stopped = GatedJobs(cooperative=False), []
    s = JobRunner(deliver=rec.deliver, job=jobs, cancelled=stopped.append)
    try:
        jobs.gate("a")
        a = s.submit(request("a"))
        assert jobs.started["a"].wait(WAIT)
        s.cancel()
        jobs.gates["a"].set()
        assert s.wait_idle(WAIT)
    finally:
        s.shutdown()
    assert jobs.chunks["a"] == jobs.steps and rec.delivered == [] and stopped == [a]


def test_any_frozen_request_with_tag_and_generation_is_numbered_keeping_its_fields(scheduler, rec, jobs):
    from dataclasses import dataclass, field

    @dataclass(frozen=True)
    class Export:                      # e.g. a report to write: the runner never looks inside
        mechanism: str
        path: str
        tag: str = "export"
        generation: int = field(default=-1, compare=False)

    jobs.gate("x", open_=True)
    numbered = scheduler.submit(Export("x", "/tmp/out"))
    assert scheduler.wait_idle(WAIT)
    assert numbered.path == "/tmp/out" and numbered.tag == "export" and numbered.generation > 0
    assert rec.delivered == [(numbered, "map of x")]


# -- the real job ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fivebar():
    preset = load_preset("fivebar_singh")
    return preset.mechanism, preset.grid


def test_the_default_job_delivers_compute_maps_result(rec, fivebar):
    mech, grid = fivebar
    small = grid.with_resolution((61, 31))
    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=run_map)
    try:
        req = s.submit(MapRequest(mech, small, ("condition_number", "isotropic_force")))
        assert s.wait_idle(WAIT)
    finally:
        s.shutdown()
    assert len(rec.delivered) == 1 and rec.delivered[0][0] == req
    result = rec.delivered[0][1]
    expected = compute_map(mech, small, ("condition_number", "isotropic_force"))
    np.testing.assert_array_equal(result.feasible, expected.feasible)
    for q in ("condition_number", "isotropic_force"):
        np.testing.assert_array_equal(result.values[q], expected.values[q])
    assert rec.progress[-1][1] == 1.0


def test_the_default_job_stops_a_superseded_map_part_way(rec, fivebar):
    """A big map superseded after its first chunk raises Cancelled and is never delivered."""
    mech, grid = fivebar
    big = grid.with_resolution((1201, 601))        # about 11 chunks
    small = grid.with_resolution((41, 21))
    outcome: dict[str, object] = {}
    s: JobRunner

    def job(req, progress, cancelled):
        def progress_then_supersede(fraction):
            progress(fraction)
            if req.stage == "big" and "newer" not in outcome:
                outcome["newer"] = s.submit(MapRequest(mech, small, ("isotropic_force",), "small"))
                outcome["fraction"] = fraction
        try:
            return run_map(req, progress_then_supersede, cancelled)
        except Cancelled:
            outcome["cancelled"] = req.stage
            raise

    s = JobRunner(deliver=rec.deliver, progress=rec.on_progress, job=job)
    try:
        s.submit(MapRequest(mech, big, ("isotropic_force",), "big"))
        assert s.wait_idle(30.0)
        assert s.wait_idle(30.0)      # the newer request was queued from inside the first job
    finally:
        s.shutdown()
    assert outcome["cancelled"] == "big" and outcome["fraction"] < 0.5
    assert [r.stage for r, _ in rec.delivered] == ["small"]
    assert rec.delivered[0][1].grid == small


def test_the_job_runner_the_requests_and_the_model_import_no_qt():
    code = ("import sys, app.jobs.runner, app.gui, app.jobs.requests, app.gui.model, app.gui.studies; "
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('PySide6', 'shiboken6', 'PyQt5', 'PyQt6')); "
            "assert not bad, bad; print('ok')")
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr


# -- the study job ---------------------------------------------------------------------------
def test_the_study_job_ranks_like_run_study_and_stops_between_chunks_when_cancelled():
    from app.gui.studies import load_study
    from metrics.design import run_study

    study = load_study("fivebar_table1")
    fractions = []
    results = run_study_job(StudyRequest(study, top_k=3), fractions.append, lambda: False)
    expected = run_study(study, workers=1, top_k=3)
    assert len(results) == 1
    np.testing.assert_array_equal(results[0].top_designs, expected.top_designs)
    np.testing.assert_array_equal(results[0].top_values, expected.top_values)
    assert fractions and fractions[-1] == 1.0 and fractions == sorted(fractions)
    with pytest.raises(Cancelled):
        run_study_job(StudyRequest(study), fractions.append, lambda: True)


def test_a_bad_study_is_the_librarys_error_naming_the_file_not_a_usage_error(tmp_path):
    from app.gui.studies import list_studies, load_study
    from resources import StudyError

    assert "fivebar_table1" in list_studies()
    with pytest.raises(StudyError, match="unknown study 'nope'; shipped: .*fivebar_table1"):
        load_study("nope")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = [", encoding="utf-8")
    with pytest.raises(StudyError, match="bad.toml"):
        load_study(str(bad))


def test_the_map_job_returns_the_map_and_what_the_views_need_of_it():
    """``run_map_for_view``: one frozen result, the map (its resolution errors with it) and the
    colour limits of the quantity the view shows, equal to those drawing the map computes."""
    from dataclasses import FrozenInstanceError

    from app.jobs.requests import run_map_for_view
    from app.logic.colour_scale import colour_scale
    from metrics.workspace import resolution_error

    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution((31, 27))
    names = ("isotropic_force", "condition_number", "bottleneck")
    for shown in names:
        result = run_map_for_view(MapRequest(preset.mechanism, grid, names, "full", "current", shown=shown),
                                  lambda f: None, lambda: False)
        with pytest.raises(FrozenInstanceError):
            result.map = None
        assert result.seconds >= result.map.seconds > 0          # the job's time holds the map's
        expected = compute_map(preset.mechanism, grid, names)
        errors = resolution_error(expected)
        assert result.map.errors.keys() == errors.keys()
        for q, figures in errors.items():            # the same map, the same statistics (nan: no estimate)
            assert np.array_equal(list(result.map.errors[q].values()), list(figures.values()), equal_nan=True), q
        if shown == "bottleneck":
            assert result.colour_limits == {}              # classes: no limits
            continue
        lo, hi, capped = result.colour_limits[shown]
        clim = colour_scale(shown, preset, [(expected.values[shown], expected.feasible)]).limits
        assert (lo, hi) == clim
    none = run_map_for_view(MapRequest(preset.mechanism, grid, names, "full", "current"), lambda f: None, lambda: False)
    assert none.colour_limits == {}


def test_a_drag_s_map_job_takes_its_legend_s_figures_alone_the_same_as_the_whole_map_s():
    """``MapRequest.figures="extremes"`` (a dragged slider's full map): the arrays, the colour limits and
    what the map's legend shows (``map_marks.extreme_marks``: the extremes, where, their errors and
    orders) are those of the map with every figure, bit for bit; its quantiles are not taken."""
    from app.jobs.requests import run_map_for_view
    from app.logic.map_marks import extreme_marks

    preset = load_preset("fivebar_singh")
    grid = preset.grid.with_resolution((131, 67))
    request = MapRequest(preset.mechanism, grid, ("isotropic_force",), "full", "current", shown="isotropic_force",
                         drag=True)
    whole = run_map_for_view(request, lambda f: None, lambda: False)
    drag = run_map_for_view(dataclasses.replace(request, figures="extremes"), lambda f: None, lambda: False)
    assert np.isfinite(whole.map.stats["isotropic_force"].median)
    assert np.isnan(drag.map.stats["isotropic_force"].median)           # (not taken)
    for a, b in ((whole.map.values["isotropic_force"], drag.map.values["isotropic_force"]),
                 (whole.map.feasible, drag.map.feasible), (whole.map.singular, drag.map.singular)):
        assert a.tobytes() == b.tobytes()
    assert drag.colour_limits == whole.colour_limits
    assert extreme_marks(drag.map, "isotropic_force") == extreme_marks(whole.map, "isotropic_force")
