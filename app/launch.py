"""The ``isoforce`` console script: the desktop app with no command, the command line otherwise.

The one module that knows both clients, so that neither imports the other: ``app.cli`` is
headless (no Qt), and the GUI is imported only when it is started.
"""
from __future__ import annotations

import gc
import signal
import sys
from typing import Sequence

#: What ``isoforce`` with no command prints when the desktop app cannot be imported.
GUI_MISSING = "the desktop app is not installed; try `isoforce --help`"


def launch_gui() -> int:
    """Start the desktop app (``app.gui.run_app``); return its exit status.

    The GUI's own broken imports (a missing PySide6, say) are raised as they are; only a
    missing GUI package prints ``GUI_MISSING`` and returns 0.
    """
    # Until the app's own handlers are set (``run_app``), Ctrl+C ends the process at once, as
    # the system's default does: a KeyboardInterrupt raised inside the start-up's imports of Qt,
    # VTK and matplotlib printed tracebacks, and once crashed the interpreter. The caller's
    # handler is back when the app returns.
    previous = signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        try:
            from app.gui import run_app
        except ImportError as exc:
            if exc.name not in ("app.gui", "app.gui.main_window"):
                raise      # the app exists but something it needs is broken: show that
            print(GUI_MISSING)
            return 0
        return int(run_app() or 0)
    finally:
        signal.signal(signal.SIGINT, previous)


def main(argv: Sequence[str] | None = None) -> int:
    """``isoforce [COMMAND ...]``: no arguments start the desktop app, else ``app.cli.main``.

    Without ``argv`` (the console script, ``python -m app``) the process is the command's own:
    its start-up runs without garbage collections and it ends without the interpreter's
    teardown, as ``python -m app.cli`` does (``app.cli._process``); ``main`` then does not return.
    """
    own_process = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        return launch_gui()
    if own_process:
        from app.cli._process import end_process, start_up_without_collections

        start_up_without_collections()
        from app.cli import main as cli_main

        end_process(cli_main(argv))
    from app.cli import main as cli_main

    status = cli_main(argv)
    # The interpreter's last act is a full garbage collection, over every object the command's
    # libraries made (~2.5 x 10^5): 0.3 s of a 2.7 s figure command. Frozen objects are left out
    # of it; they are freed with the process anyway (``atexit`` handlers still run first).
    gc.freeze()
    return status
