"""Progress of a long job on stderr: a bar on a terminal, a line every few seconds otherwise.

Only jobs predicted to take longer than ``PROGRESS_AFTER`` report; a short one stays silent,
and so does one whose stdout is JSON while stderr is not a terminal (a script reading both).
Every line starts ``isoforce COMMAND:``, like the program's other notes. The clock is a
parameter, so the output is tested without waiting.
"""
from __future__ import annotations

import sys
import time
from typing import Callable, TextIO

from metrics.runtime import format_duration

#: Jobs predicted to take longer than this (seconds) report their progress.
PROGRESS_AFTER = 10.0
#: Seconds between lines when stderr is not a terminal.
LINE_EVERY = 10.0
#: Seconds between redraws of the bar on a terminal.
BAR_EVERY = 0.2
BAR_WIDTH = 24
#: Share of a job done from which its time left is read from its own pace alone.
TRUST_AFTER = 0.2


class Progress:
    """A progress callback (``fraction`` 0 to 1 of the whole job) that writes to ``stream``.

    Parameters
    ----------
    label : str
        The line's start, e.g. ``"isoforce stats"``.
    points : int
        Points in the whole job (for the text).
    stream : file, optional
        Default ``sys.stderr``.
    terminal : bool, optional
        Draw a bar redrawn in place (default: whether ``stream`` is a terminal).
    clock : callable ``() -> float``
        Seconds.
    predicted : float, optional
        The job's predicted seconds (from a sample of its whole range). Early on, the time left
        leans on it: a grid's first chunks are a corner of its range, often infeasible and
        several times faster than its interior; from ``TRUST_AFTER`` done on, on the pace seen.
    """

    def __init__(self, label: str, points: int, *, stream: TextIO | None = None, terminal: bool | None = None,
                 clock: Callable[[], float] = time.monotonic, predicted: float | None = None):
        self.label, self.points, self.predicted = label, int(points), predicted
        self.stream = sys.stderr if stream is None else stream
        self.terminal = _isatty(self.stream) if terminal is None else bool(terminal)
        self.clock = clock
        self.start = clock()
        self.last = self.start
        self.fraction = 0.0
        self.drawn = 0

    def part(self, done: int, points: int) -> Callable[[float], None]:
        """The callback of one map of the job: ``points`` of them, after ``done`` points of earlier maps."""
        return lambda fraction: self(min(1.0, (done + fraction * points) / max(1, self.points)))

    def __call__(self, fraction: float) -> None:
        self.fraction = fraction
        now = self.clock()
        if now - self.last < (BAR_EVERY if self.terminal else LINE_EVERY) or fraction >= 1.0:
            return
        self.last = now
        self._write(now)

    def left(self, now: float) -> float | None:
        """Seconds left: the pace seen so far, weighed against the prediction until ``TRUST_AFTER`` is done."""
        f, elapsed = self.fraction, now - self.start
        seen = elapsed * (1.0 - f) / f if f > 0 else None
        if self.predicted is None:
            return seen
        expected = self.predicted * (1.0 - f)
        if seen is None:
            return expected
        w = min(1.0, f / TRUST_AFTER)
        return w * seen + (1.0 - w) * expected

    def text(self, now: float) -> str:
        """``"isoforce stats: 42% of 512,000,000 points, 2 min elapsed, about 3 min left"``."""
        f, elapsed, left = self.fraction, now - self.start, self.left(now)
        eta = f"about {format_duration(left)} left" if left is not None else "starting"
        percent = f"{100 * f:3.0f}%" if f == 0 or f >= 0.01 else f"{100 * f:.1g}%"
        if self.terminal:
            filled = int(BAR_WIDTH * f)
            return f"{self.label}: [{'#' * filled}{'-' * (BAR_WIDTH - filled)}] {percent}  {eta}"
        return (f"{self.label}: {percent.strip()} of {self.points:,} points, {format_duration(elapsed)} elapsed, "
                f"{eta}")

    def _write(self, now: float) -> None:
        line = self.text(now)
        if self.terminal:
            self.stream.write("\r" + line.ljust(self.drawn))
            self.drawn = len(line)
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def close(self) -> None:
        """Clear the bar (a terminal), so that the next line starts clean."""
        if self.terminal and self.drawn:
            self.stream.write("\r" + " " * self.drawn + "\r")
            self.stream.flush()
            self.drawn = 0

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class _Silent:
    """The callback of a job that reports nothing."""

    def part(self, done: int, points: int) -> None:
        return None

    def __call__(self, fraction: float) -> None:
        return None

    def __enter__(self) -> "_Silent":
        return self

    def __exit__(self, *exc) -> None:
        return None


def progress_for(label: str, seconds: float | None, points: int, *, json_out: bool = False,
                 stream: TextIO | None = None) -> Progress | _Silent:
    """The progress reporter of a job predicted to take ``seconds`` (None: not predicted, so short).

    Parameters
    ----------
    label : str
        The lines' start, ``"isoforce COMMAND"``.
    seconds : float or None
        The job's predicted run time (``metrics.runtime.Prediction.seconds``).
    points : int
        Points in the job.
    json_out : bool
        stdout carries JSON: report only to a terminal.
    stream : file, optional
        Default ``sys.stderr``.

    Returns
    -------
    Progress or a silent stand-in
        Use as a context manager; call it (or its ``part``) as ``compute_map``'s ``progress``.
    """
    stream = sys.stderr if stream is None else stream
    if seconds is None or seconds <= PROGRESS_AFTER or (json_out and not _isatty(stream)):
        return _Silent()
    return Progress(label, points, stream=stream, predicted=seconds)
