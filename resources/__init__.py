"""Device presets and design studies shipped as TOML package data, and the schemas that read them.

No Qt; depends on ``kinematics`` only.
"""
from __future__ import annotations

from kinematics.lazy import public_names

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

#: The study files' names, imported from their modules on first use (PEP 562 ``__getattr__``):
#: every command reads a preset, few read a study (its eight modules, 10-20 ms).
_STUDY = {"StudyError": "study_file", "StudyFile": "study_file", "list_studies": "study_schema",
          "load_study": "study_schema"}

__all__ = ["MECHANISMS", "Preset", "PresetError", "list_presets", "load_preset", "read_preset_file",
           "preset_to_toml", "parse_preset_text", "StudyError", "StudyFile", "list_studies", "load_study"]


__getattr__, __dir__ = public_names(__name__, _STUDY)
