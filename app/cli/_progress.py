"""Progress of a long job on stderr: a rich bar on a terminal, a line every few seconds otherwise.

A job shows its progress once it is predicted to take longer than ``PROGRESS_AFTER`` (from
``metrics.runtime``, where the command predicts), or, when it was not predicted or predicted
short, once it has run that long; a short job stays silent.

- On a terminal: a ``rich`` progress bar with the share done, the time elapsed and the time
  left, redrawn in place and cleared when the job ends (the command's output then starts clean).
- Elsewhere (a pipe, a log file): a plain line every ``LINE_EVERY`` seconds, starting
  ``isoforce COMMAND:`` like the program's other notes, so a job shorter than that prints none.
- With ``--json`` while stderr is not a terminal: nothing (a script reading both streams).
  stdout never carries progress: with ``--json`` it is exactly one JSON object.

The clock is a parameter (``rich`` reads the same one), so the output is tested without waiting.
"""
from __future__ import annotations

import sys
import threading
import time
from typing import Any, Callable, TextIO

from metrics.runtime import format_duration

#: Jobs predicted (or seen) to take longer than this (seconds) report their progress.
PROGRESS_AFTER = 2.0
#: Seconds between lines when stderr is not a terminal.
LINE_EVERY = 5.0
#: Characters of the bar on a terminal (the step's name and the times beside it need room).
BAR_WIDTH = 20
#: Redraws of the bar a second on a terminal (rich's refresh thread).
REDRAWS_PER_SECOND = 5
#: Seconds between the reporting thread's looks at the job (with the real clock).
TICK = 0.25
#: Share of a job done from which its time left is read from its own pace alone.
TRUST_AFTER = 0.2

_KEEP = object()


class Progress:
    """A progress callback (``fraction`` 0 to 1 of the whole job) that reports on ``stream``.

    Use it as a context manager (or ``close`` it): it may run a thread and draw a bar.

    Parameters
    ----------
    label : str
        The line's start, e.g. ``"isoforce stats"``.
    points : int, optional
        Units of work in the whole job (for the text; None: not said).
    unit : str
        What ``points`` counts (``"points"``, ``"designs"``, ``"devices"``).
    stream : file, optional
        Default ``sys.stderr``.
    terminal : bool, optional
        Draw a bar redrawn in place (default: whether ``stream`` is a terminal).
    clock : callable ``() -> float``
        Seconds.
    predicted : float, optional
        The job's predicted seconds (from a sample of its whole range). Above ``PROGRESS_AFTER``
        the bar shows at once, else from ``PROGRESS_AFTER`` seconds on. Early on, the time
        left leans on it: a grid's first chunks are a corner of its range, often infeasible and
        several times faster than its interior; from ``TRUST_AFTER`` done on, on the pace seen.
    refresh_thread : bool, optional
        Report on a thread too (every ``TICK`` seconds; rich redraws the bar on its own), so
        the bar appears, the times tick and the lines come while a step runs long between
        calls (default: with the real clock; with a test's clock, only the calls report).
    """

    def __init__(self, label: str, points: int | None = None, *, unit: str = "points",
                 stream: TextIO | None = None, terminal: bool | None = None,
                 clock: Callable[[], float] = time.monotonic, predicted: float | None = None,
                 refresh_thread: bool | None = None):
        self.label, self.unit, self.predicted = label, unit, predicted
        self.points = None if points is None else int(points)
        self.stream = sys.stderr if stream is None else stream
        self.terminal = _isatty(self.stream) if terminal is None else bool(terminal)
        self.clock = clock
        self.refresh_thread = (clock is time.monotonic) if refresh_thread is None else bool(refresh_thread)
        self.start = clock()
        self.last = self.start
        #: Share done, or None while the current step's share is unknown.
        self.fraction: float | None = 0.0
        #: The step under way (e.g. ``"map 500 x 250"``), said after the label; "" for none.
        self.stage = ""
        #: (time, share) the pace is measured from.
        self.pace_from = (self.start, 0.0)
        self._bar: Any = None
        self._task: Any = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None
        if self.refresh_thread:
            self._ticker = threading.Thread(target=self._tick, name="isoforce-progress", daemon=True)
            self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(TICK):
            self._report()

    def part(self, done: int, points: int) -> Callable[[float], None]:
        """The callback of one part of the job: ``points`` of them, after ``done`` points of earlier parts."""
        total = max(1, self.points or 1)
        return lambda fraction: self(min(1.0, (done + fraction * points) / total))

    def __call__(self, fraction: float) -> None:
        self._set(float(fraction))
        self._report()

    def step(self, message: str, fraction: Any = _KEEP) -> None:
        """Name the step under way; ``fraction`` the share done (None: unknown), default unchanged."""
        self.stage = message
        if fraction is not _KEEP:
            self._set(None if fraction is None else float(fraction))
        self._report()

    def _set(self, fraction: float | None) -> None:
        # A share that goes back (a dextrous box grown, work found after a step of unknown
        # share) starts the pace afresh: the time before it says nothing of the work ahead.
        if fraction is not None and (self.fraction is None or fraction < self.fraction):
            self.pace_from, self.predicted = (self.clock(), fraction), None
        self.fraction = fraction

    def left(self, now: float) -> float | None:
        """Seconds left: the pace seen so far, weighed against the prediction until ``TRUST_AFTER`` is done."""
        f = self.fraction
        if f is None:
            return None
        t0, f0 = self.pace_from
        seen = (now - t0) * (1.0 - f) / (f - f0) if f > f0 else None
        if self.predicted is None:
            return seen
        expected = self.predicted * (1.0 - f)
        if seen is None:
            return expected
        w = min(1.0, f / TRUST_AFTER)
        return w * seen + (1.0 - w) * expected

    def times(self, now: float) -> str:
        """``"2 min elapsed, about 3 min left"`` (the bar's right-hand column, the line's end)."""
        left = None if self._done() else self.left(now)
        elapsed = f"{format_duration(now - self.start) if now > self.start else '0 s'} elapsed"
        if left is not None:
            return f"{elapsed}, about {format_duration(max(left, 0.1))} left"
        return elapsed + (", starting" if self.fraction == 0 else "")

    def text(self, now: float) -> str:
        """The line: ``"isoforce stats: 42% of 512,000,000 points, 2 min elapsed, about 3 min left"``."""
        head = f"{self.label}: " + (f"{self.stage}, " if self.stage else "")
        f = self.fraction
        if f is None:
            return head + self.times(now)
        percent = f"{100 * f:.0f}%" if f == 0 or f >= 0.01 else f"{100 * f:.1g}%"
        of = f" of {self.points:,} {self.unit}" if self.points is not None else ""
        return f"{head}{percent}{of}, {self.times(now)}"

    # -- output ------------------------------------------------------------------------------
    def _done(self) -> bool:
        return self.fraction is not None and self.fraction >= 1.0

    def _report(self) -> None:
        with self._lock:
            if not self._stop.is_set():
                self._report_now()

    def _report_now(self) -> None:
        now = self.clock()
        if self.terminal:
            if self._bar is None:
                seen = now - self.start >= PROGRESS_AFTER
                if self._done() or not (seen or (self.predicted is not None and self.predicted > PROGRESS_AFTER)):
                    return
                self._open()
            self._draw()
            return
        if now - self.last < LINE_EVERY or self._done():
            return
        self.last = now
        self.stream.write(self.text(now) + "\n")
        self.stream.flush()

    def _open(self) -> None:
        # rich only when a bar is drawn: a pipe's run and a short one never import it.
        from rich.console import Console
        from rich.progress import BarColumn, TaskProgressColumn, TextColumn
        from rich.progress import Progress as Bar
        from rich.table import Column

        console = Console(file=self.stream, force_terminal=True, force_interactive=True, highlight=False,
                          get_time=self.clock)
        name = TextColumn("{task.description}", table_column=Column(no_wrap=True))
        self._bar = Bar(name, BarColumn(bar_width=BAR_WIDTH), TaskProgressColumn(),
                        _times_column(self), console=console, auto_refresh=self.refresh_thread,
                        refresh_per_second=REDRAWS_PER_SECOND, transient=True, redirect_stdout=False,
                        redirect_stderr=False, get_time=self.clock)
        self._task = self._bar.add_task(self._description(), total=1.0)
        self._draw()
        self._bar.start()

    def _description(self) -> str:
        """The label and the step, the step cut short to leave the bar and the times room on the line."""
        stage = self.stage
        room = self._bar.console.width - len(self.label) - 2 - BAR_WIDTH - 6 - len(self.times(self.clock())) - 2
        if len(stage) > max(room, 8):
            stage = stage[:max(room, 8) - 1] + "…"
        return f"{self.label}:" + (f" {stage}" if stage else "")

    def _draw(self) -> None:
        f = self.fraction
        self._bar.update(self._task, description=self._description(), completed=0.0 if f is None else min(1.0, f))
        # An unknown share: no total, so rich pulses the bar and says no percentage.
        self._bar.tasks[0].total = None if f is None else 1.0
        if not self.refresh_thread:
            self._bar.refresh()

    def close(self) -> None:
        """Stop reporting and clear the bar (a terminal), so that the next line starts clean."""
        self._stop.set()
        if self._ticker is not None and self._ticker is not threading.current_thread():
            self._ticker.join()
        with self._lock:
            if self._bar is not None:
                self._bar.stop()
                self._bar = None

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _times_column(owner: Progress):
    """rich's column of ``owner.times`` (a class made here: rich is imported only to draw)."""
    from rich.progress import ProgressColumn
    from rich.table import Column
    from rich.text import Text

    class Times(ProgressColumn):
        """The time elapsed and left, as the non-terminal line says them."""

        def __init__(self, owner: Progress) -> None:
            super().__init__(table_column=Column(no_wrap=True))
            self.owner = owner

        def render(self, task) -> Text:
            return Text(self.owner.times(self.owner.clock()), style="progress.remaining")

    return Times(owner)


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class _Silent:
    """The callback of a job that reports nothing."""

    def part(self, done: int, points: int) -> None:
        return None

    def step(self, message: str, fraction: Any = _KEEP) -> None:
        return None

    def __call__(self, fraction: float) -> None:
        return None

    def __enter__(self) -> "_Silent":
        return self

    def __exit__(self, *exc) -> None:
        return None


def progress_for(label: str, seconds: float | None, points: int | None, *, json_out: bool = False,
                 stream: TextIO | None = None, unit: str = "points", terminal: bool | None = None,
                 clock: Callable[[], float] = time.monotonic) -> Progress | _Silent:
    """The progress reporter of a job predicted to take ``seconds`` (None: not predicted).

    Parameters
    ----------
    label : str
        The lines' start, ``"isoforce COMMAND"``.
    seconds : float or None
        The job's predicted run time (``metrics.runtime.Prediction.seconds``).
    points : int or None
        Units of work in the job.
    json_out : bool
        stdout carries JSON: report only to a terminal.
    stream : file, optional
        Default ``sys.stderr``.
    unit, terminal, clock
        As ``Progress`` takes them.

    Returns
    -------
    Progress or a silent stand-in
        Use as a context manager; call it (or its ``part``) as ``compute_map``'s ``progress``.

    Examples
    --------
    >>> import io
    >>> now = [0.0]
    >>> with progress_for("isoforce map", None, 100, stream=io.StringIO(), terminal=False,
    ...                   clock=lambda: now[0]) as p:
    ...     now[0] = 6.0
    ...     p(0.25)
    >>> p.stream.getvalue()
    'isoforce map: 25% of 100 points, 6 s elapsed, about 18 s left\\n'
    """
    stream = sys.stderr if stream is None else stream
    is_terminal = _isatty(stream) if terminal is None else terminal
    if json_out and not is_terminal:
        return _Silent()
    return Progress(label, points, unit=unit, stream=stream, terminal=is_terminal, clock=clock, predicted=seconds)
