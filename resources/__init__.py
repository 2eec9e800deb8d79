"""Device presets and design studies shipped as TOML package data, and the schemas that read them.

No Qt; depends on ``kinematics`` only.
"""
from __future__ import annotations

from .schema import (
    MECHANISMS,
    Preset,
    PresetError,
    list_presets,
    load_preset,
    parse_preset_text,
    preset_to_toml,
    read_preset_file,
)
from .study_file import StudyError, StudyFile
from .study_schema import list_studies, load_study

__all__ = ["MECHANISMS", "Preset", "PresetError", "list_presets", "load_preset", "read_preset_file",
           "preset_to_toml", "parse_preset_text", "StudyError", "StudyFile", "list_studies", "load_study"]

