"""The desktop app (PySide6 + PyVista): ``run_app`` starts it, ``MainWindow`` is its window.

Qt-free parts, importable and testable without a display: ``model`` (the app's state and
its events), ``requests`` (the maps and studies run in the background) and ``studies``.
Qt is imported only when ``run_app`` or ``MainWindow`` is first used, so ``import app.gui.model``
stays headless.
"""
from __future__ import annotations

__all__ = ["MainWindow", "run_app"]


def __getattr__(name: str):
    # PEP 562: the Qt window is imported on first use, not when a Qt-free submodule is.
    if name in __all__:
        from app.gui import main_window
        return vars(main_window)[name]
    raise AttributeError(f"module 'app.gui' has no attribute {name!r}")
