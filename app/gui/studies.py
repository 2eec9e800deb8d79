"""Design studies for the Optimize panel: the shipped ones by key, or a TOML file by path.

Read through the library (``resources.load_study``, then ``metrics.design.build_study``),
never through the command line, so a bad study raises the library's ``StudyError`` (a
``ValueError`` naming the file and key), which the panel and its error dialog show as it is.
"""
from __future__ import annotations

from metrics.design import Study, build_study
from resources import list_studies
from resources import load_study as load_study_file

__all__ = ["list_studies", "load_study"]


def load_study(name: str) -> Study:
    """The searchable study ``name``: a shipped study's key, or a path to a ``.toml`` file.

    Raises
    ------
    resources.StudyError
        The study is unknown, unreadable or invalid; the message names the file and key.
    ValueError
        A design of the study that the mechanism refuses (the message says which).
    """
    return build_study(load_study_file(name))
