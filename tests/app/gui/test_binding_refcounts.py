"""The Qt binding keeps Python's ``None`` alive: no QPainter call the app makes drops a reference.

PySide6-Essentials 6.12.0 on Python 3.11 takes one reference off ``None`` at every call of a
QPainter method that returns nothing (``setBrush`` -1 per call, ``save`` + ``restore`` -2), and
Python 3.11's ``None`` is not immortal: the app aborts in ``none_dealloc`` after 200-250 edits
(issue 21 sec. 0). ``pyproject.toml`` excludes that release; this test fails on it, or on any
later one that does the same.

Each call the app makes (``CALLS``: every QPainter method in ``app/gui``, with the argument
types it passes) runs in batches of ``BATCH`` into a ``QImage``, in a child process (an abort
there fails this test instead of ending the session, and no worker thread of another test
moves the count meanwhile). A call fails as soon as ``sys.getrefcount(None)`` has moved by
more than ``TOLERANCE`` since before its first batch.

The tolerance: with a sound binding the count at the same point of the loop is the same
(measured 0 over 2,000 calls of every method with 6.11.3; the loop's own temporaries are
released before each reading). ``TOLERANCE = 4`` leaves room for an interpreter that caches
a few objects holding ``None`` on first use, and is 25 times smaller than what a leak of one
reference per call loses in one batch of 100 (6.12.0: -100, -200 for save + restore), so the
first batch shows it; a leak of one reference in every 400 calls also fails over the 2,000.

Run by hand with another interpreter: ``QT_QPA_PLATFORM=offscreen python tests/app/gui/test_binding_refcounts.py``
prints one JSON line per call.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

#: Calls per batch, batches per call (2,000 calls of each), and the drift allowed (module docstring).
BATCH, BATCHES, TOLERANCE = 100, 20, 4


def painter_calls():
    """``{label: call(painter)}``: each QPainter method ``app/gui`` uses, with the argument types it passes
    (``views/map_canvas.py``, ``views/plotter_widget.py``)."""
    from PySide6.QtCore import QLineF, QPointF, QRect, QRectF, Qt
    from PySide6.QtGui import QBrush, QColor, QFont, QImage, QPainter, QPainterPath, QPen, QPolygonF

    image = QImage(16, 16, QImage.Format.Format_RGB32)
    image.fill(QColor("white"))
    rect, rectf = QRect(2, 2, 40, 30), QRectF(2.5, 2.5, 40.0, 30.0)
    pen, brush, font = QPen(QColor("black"), 1.5), QBrush(QColor("#17becf")), QFont()
    colour = QColor(255, 255, 255, 200)
    polygon = QPolygonF([QPointF(1, 1), QPointF(20, 5), QPointF(8, 25)])
    path = QPainterPath()
    path.moveTo(1, 1)
    path.lineTo(30, 20)
    centre = QPointF(30.0, 30.0)
    flags = int(Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap)
    return {
        "save + restore": lambda p: (p.save(), p.restore()),
        "setPen(QPen)": lambda p: p.setPen(pen),
        "setPen(QColor)": lambda p: p.setPen(colour),
        "setPen(GlobalColor)": lambda p: p.setPen(Qt.GlobalColor.black),
        "setBrush(QBrush)": lambda p: p.setBrush(brush),
        "setBrush(QColor)": lambda p: p.setBrush(colour),
        "setBrush(BrushStyle)": lambda p: p.setBrush(Qt.BrushStyle.NoBrush),
        "setFont": lambda p: p.setFont(font),
        "setRenderHint": lambda p: p.setRenderHint(QPainter.RenderHint.Antialiasing, True),
        "setClipRect(QRectF)": lambda p: p.setClipRect(rectf),
        "setClipRect(QRect)": lambda p: p.setClipRect(rect),
        "translate(QPointF)": lambda p: p.translate(centre),
        "translate(x, y)": lambda p: p.translate(1.0, -1.0),
        "rotate": lambda p: p.rotate(-90.0),
        "fillRect(QRect, GlobalColor)": lambda p: p.fillRect(rect, Qt.GlobalColor.white),
        "fillRect(QRectF, QColor)": lambda p: p.fillRect(rectf, colour),
        "fillRect(QRectF, QBrush)": lambda p: p.fillRect(rectf, QBrush(colour, Qt.BrushStyle.BDiagPattern)),
        "drawText(QRect, flags, str)": lambda p: p.drawText(rect, flags, "map"),
        "drawText(QRectF, flags, str)": lambda p: p.drawText(rectf, flags, "12.5 N"),
        "drawImage(QRectF, QImage)": lambda p: p.drawImage(rectf, image),
        "drawImage(QRect, QImage)": lambda p: p.drawImage(rect, image),
        "drawImage(x, y, QImage)": lambda p: p.drawImage(0, 0, image),
        "drawLine(QLineF)": lambda p: p.drawLine(QLineF(1.0, 2.0, 30.0, 40.0)),
        "drawRect(QRectF)": lambda p: p.drawRect(rectf),
        "drawRoundedRect": lambda p: p.drawRoundedRect(rectf, 3, 3),
        "drawEllipse(QPointF, rx, ry)": lambda p: p.drawEllipse(centre, 5.0, 3.0),
        "drawPolyline": lambda p: p.drawPolyline(polygon),
        "drawPolygon": lambda p: p.drawPolygon(polygon),
        "drawPath": lambda p: p.drawPath(path),
    }


def measure() -> int:
    """Print ``{"call", "drift", "calls"}`` per call, then ``{"measured": n}``; stop at the first
    call that drifts and return 1."""
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QGuiApplication, QImage, QPainter

    app = QGuiApplication.instance() or QGuiApplication([])    # noqa: F841 (fonts need one)
    target = QImage(200, 150, QImage.Format.Format_ARGB32_Premultiplied)
    target.fill(Qt.GlobalColor.white)
    calls = painter_calls()
    for label, call in calls.items():
        painter = QPainter(target)
        for _ in range(10):                        # first-use caches (fonts, glyphs) filled first
            call(painter)
        start, done, drift = sys.getrefcount(None), 0, 0
        while done < BATCH * BATCHES and abs(drift) <= TOLERANCE:
            for _ in range(BATCH):
                call(painter)
            done += BATCH
            drift = sys.getrefcount(None) - start
        painter.end()
        print(json.dumps({"call": label, "drift": drift, "calls": done}), flush=True)
        if abs(drift) > TOLERANCE:
            return 1            # a broken binding: stopped before None's count gets near zero
    print(json.dumps({"measured": len(calls)}), flush=True)
    return 0


def test_no_qpainter_call_drops_a_reference_to_none():
    import PySide6
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    run = subprocess.run([sys.executable, __file__], env=env, capture_output=True, text=True, timeout=300)
    rows = [json.loads(line) for line in run.stdout.splitlines() if line.startswith("{")]
    drifted = [row for row in rows if abs(row.get("drift", 0)) > TOLERANCE]
    assert not drifted, (f"PySide6 {PySide6.__version__}: sys.getrefcount(None) moved by {drifted[0]['drift']} "
                         f"over {drifted[0]['calls']} calls of QPainter.{drifted[0]['call']} (tolerance {TOLERANCE}); "
                         "this binding ends a session in none_dealloc (pyproject.toml excludes it)")
    assert run.returncode == 0, f"the probe ended with status {run.returncode}:\n{run.stderr[-2000:]}"
    # Every call measured: the child lists them all when none drifted.
    assert rows and rows[-1] == {"measured": len(rows) - 1}, run.stdout[-2000:] + run.stderr[-2000:]


if __name__ == "__main__":
    sys.exit(measure())
