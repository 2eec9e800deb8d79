"""Device presets and design studies shipped as TOML package data, and the schemas that read them.

No Qt; depends on ``kinematics`` only.
"""
from __future__ import annotations

from importlib import resources as _res
from pathlib import Path

from .schema import MECHANISMS, Preset, PresetError, parse_preset_text, preset_to_toml, read_preset_file
from .study_file import StudyError, StudyFile
from .study_schema import list_studies, load_study

__all__ = ["MECHANISMS", "Preset", "PresetError", "list_presets", "load_preset", "read_preset_file",
           "preset_to_toml", "parse_preset_text", "StudyError", "StudyFile", "list_studies", "load_study"]


def list_presets() -> list[str]:
    """Keys of the shipped presets (file stems), sorted."""
    folder = _res.files(__package__).joinpath("presets")
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_preset(name: str) -> Preset:
    """A shipped preset by key, or a TOML file by path (anything ending in ``.toml``)."""
    if name.endswith(".toml") or "/" in name:
        return read_preset_file(Path(name))
    known = list_presets()
    if name not in known:
        raise PresetError(f"unknown device {name!r}; known: {', '.join(known)} (or a path to a .toml file)")
    text = _res.files(__package__).joinpath("presets", f"{name}.toml").read_text(encoding="utf-8")
    return parse_preset_text(text, f"{name}.toml", name)
