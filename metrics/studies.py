"""Compatibility names for callers not yet moved to ``metrics.design`` and ``resources.load_study``.

Temporary (issue 8): ``app/optimize_cli.py`` (moving to ``app/cli/``), ``app/gui/studies.py``,
``app/gui/requests.py``, ``app/gui/optimise.py``, ``scripts/bench_optimize.py``. New code reads
a study with ``resources.load_study`` and builds it with ``metrics.design.build_study``. This
module imports ``resources`` inside its two reader functions, which the layers otherwise
forbid in ``metrics``: delete it once those callers have switched.
"""
from __future__ import annotations

from pathlib import Path

from .design import *  # noqa: F401,F403
from .design import Study, build_study


def parse_study_text(text: str, source: str, key: str = "", *, load_preset=None) -> Study:
    """``build_study(resources.study_schema.parse_study_text(...))`` (``load_preset`` is unused:
    ``resources`` reads presets itself)."""
    from resources.study_schema import parse_study_text as read
    return build_study(read(text, source, key))


def read_study_file(path: str | Path, *, load_preset=None) -> Study:
    """``build_study(resources.study_schema.read_study_file(path))``."""
    from resources.study_schema import read_study_file as read
    return build_study(read(path))


def __getattr__(name: str):
    if name == "StudyError":
        from resources import StudyError
        return StudyError
    raise AttributeError(name)
