"""Preset files the tests write: variants of shipped presets under the same key."""
from __future__ import annotations

from resources import load_preset, preset_to_toml


def massless_omni(folder) -> str:
    """The PHANToM Omni preset with ``mass_model = "none"`` as a file ``phantom_omni.toml`` (key
    ``phantom_omni``) in ``folder``: a device without a mass model, now that the shipped Omni has
    an estimated one. Returns the file's path."""
    preset = load_preset("phantom_omni")
    path = folder / "phantom_omni.toml"
    path.write_text(preset_to_toml(preset.replace(mechanism=preset.mechanism.replace(mass_model="none"))),
                    encoding="utf-8")
    return str(path)
