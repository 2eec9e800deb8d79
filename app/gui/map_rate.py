"""How fast maps compute on this machine in this session: whether a slider step needs a preview.

A map whose full resolution computes within a frame (``FRAME_S``) needs no coarse stand-in:
a slider step asks for it directly. Which maps those are is measured, never listed per device:
every map the app computed adds its points and seconds (``MapResult.seconds``, its job's time:
the map and its colour limits) to ``MapRates`` under the kind of work it was (the mechanism's
model, the quantities, one core or all; ``rate_key``), and ``MapRates.seconds`` predicts a map
of that kind:

- at a size computed before, the median of its last ``KEPT`` times;
- at another size, that many points at the median rate (points per second) of the kind's last
  ``KEPT`` maps. A small map's fixed cost lowers its rate, so a map larger than those is
  predicted too slow rather than too fast: one that would miss its frame is not taken for one
  that makes it. Recent maps only: one slow map (the map worker's first, loading the compiled
  kernels, took ~1 s for 14,400 points) must not size every preview after it.

A kind never measured has no prediction (``None``): the coarse-then-full path, which is always
right, only slower. No Qt here (tested in ``tests/app/gui/test_map_rate.py``).

How a map was computed is part of its kind (``rate_key``'s ``threads``): a full map runs over the
cores in the app's process, a coarse one on one core in the map worker process
(``app.jobs.map_worker``), and a size's time predicts only maps computed the same way. Mixed, the
Inverse3's dragged full map (the map view's isotropic force alone, 10^6 points) was predicted at
241 ms from its 120 x 120 previews while it computes in ~45-55 ms on two threads (load 2, its
statistics included): a preview's time is mostly the map's fixed cost (planning, the singular
extremes, the statistics' set-up: ~1.7-3.5 ms for 14,400 points, ~120-240 ns a point against
~45-50 ns a point at 10^6) and one core's. A kind's full size is then measured outright
(``MainWindow._probe_drag_rate``) rather than extrapolated.
"""
from __future__ import annotations

import statistics
from collections import deque

#: One frame of a 60 Hz display, s: a map computed within it needs no preview while a slider moves.
#: The budget of a dragged slider's map, a design choice: a step's map must be on screen before the
#: next step supersedes it (a result that arrives later is never shown: ``JobRunner``'s newest
#: wins), 33 ms apart at a 30 Hz drag, and the GUI thread needs the rest of that interval for the
#: same step's glyphs (~10-25 ms) and to apply, colour (~700 x 900 px) and paint the map. So the
#: map computes within the first frame and is shown in the second; a budget of the whole 33 ms
#: would leave nothing for showing it, and a map slower than a frame is previewed coarse.
FRAME_S = 1 / 60
#: Times kept per kind and size (their median is the prediction at that size).
KEPT = 3


def rate_key(mechanism, quantities, threads: bool = True) -> tuple:
    """What makes two maps cost the same per point: the mechanism's model, the quantities, and
    whether the map ran over the cores (``threads``: a full map) or on one (a coarse map)."""
    return (type(mechanism).__qualname__, tuple(sorted(quantities))) + (() if threads else ("one core",))


class MapRates:
    """Measured compute times of maps, by kind (``rate_key``) and number of points."""

    def __init__(self) -> None:
        self._times: dict[tuple, dict[int, deque]] = {}     # key -> points -> last times, s
        self._rates: dict[tuple, deque] = {}                # key -> last rates, points/s
        self._bounds: dict[tuple, deque] = {}               # (key, points) -> whether each kept time is a bound

    def add(self, key: tuple, points: int, seconds: float, *, bound: bool = False) -> None:
        """Record one map of ``key`` with ``points`` points computed in ``seconds``; ``bound``: it was
        stopped unfinished after ``seconds`` (a lower bound of its time, ``MainWindow._superseded``)."""
        if points <= 0 or not seconds > 0:          # (nan or an empty map says nothing of a rate)
            return
        self._times.setdefault(key, {}).setdefault(int(points), deque(maxlen=KEPT)).append(float(seconds))
        self._rates.setdefault(key, deque(maxlen=KEPT)).append(int(points) / float(seconds))
        self._bounds.setdefault((key, int(points)), deque(maxlen=KEPT)).append(bool(bound))

    def bounded(self, key: tuple, points: int) -> bool:
        """Whether any time kept for ``key`` at ``points`` points is a lower bound only (their median,
        the prediction, may then be one: ``MainWindow._probe_drag_rate`` times that kind again)."""
        return any(self._bounds.get((key, int(points)), ()))

    def points_per_second(self, key: tuple) -> float | None:
        """The median rate of the last ``KEPT`` maps of ``key``, or None if none was measured."""
        rates = self._rates.get(key)
        return statistics.median(rates) if rates else None

    def seconds(self, key: tuple, points: int) -> float | None:
        """The predicted compute time of a map of ``key`` with ``points`` points, or None if unmeasured."""
        times = self._times.get(key, {}).get(int(points))
        if times:
            return statistics.median(times)
        rate = self.points_per_second(key)
        return None if rate is None else int(points) / rate

    def measured(self, key: tuple, points: int) -> int:
        """How many times are kept for ``key`` at exactly ``points`` points (at most ``KEPT``; ``seconds``
        is then their median, no extrapolation)."""
        return len(self._times.get(key, {}).get(int(points), ()))

    def within_frame(self, key: tuple, points: int, frame_s: float = FRAME_S) -> bool:
        """Whether a map of ``key`` with ``points`` points is predicted to compute within ``frame_s``."""
        predicted = self.seconds(key, points)
        return predicted is not None and predicted <= frame_s
