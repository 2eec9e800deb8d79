"""Write a commented example device file per mechanism family into ``docs/examples/``.

    python scripts/example_devices.py [--check]

Each file is a shipped preset of that family written back as TOML, with a comment above every
parameter giving its meaning and unit, so a designer can copy it, change the numbers and load
it: ``isoforce stats my_device.toml`` or File > Open device in the app. ``--check`` exits 1
when a file differs from what would be written (the test suite runs it).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from kinematics import MECHANISMS  # noqa: E402
from resources import list_presets, load_preset, preset_to_toml  # noqa: E402

OUT = ROOT / "docs" / "examples"
HEADER = """# Example {kind} device ({cls}), written from the shipped preset '{key}' by
# scripts/example_devices.py. Copy it, change the numbers, then:
#   isoforce show my_device.toml      isoforce stats my_device.toml      (app: File > Open device)
# Units are the ones a person types: mm and deg for lengths and angles, N m for torques.
# An unknown or bad key is an error naming this file and the key.
"""


def example_text(kind: str) -> str:
    """The commented TOML of the first shipped preset of ``kind``."""
    key = next(k for k in list_presets() if load_preset(k).kind == kind)
    preset = load_preset(key)
    infos = {info.name: info for info in preset.mechanism.PARAM_INFO}
    lines, section = [], ""
    for line in preset_to_toml(preset).splitlines():
        if line.startswith("["):
            section = line.strip("[] ")
        name = line.split("=", 1)[0].strip() if "=" in line and section == "parameters" else None
        info = infos.get(name)
        if info is not None:
            unit = f" [{info.unit}]" if info.unit else ""
            labels = f" ({', '.join(info.labels)})" if info.labels else ""
            choices = f"; one of {', '.join(info.choices)}" if info.choices else ""
            lines.append(f"# {info.description}{unit}{labels}{choices}")
        lines.append(line)
    return HEADER.format(kind=kind, cls=MECHANISMS[kind].__name__, key=key) + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if a file is out of date")
    args = parser.parse_args(argv)
    stale = []
    OUT.mkdir(parents=True, exist_ok=True)
    for kind in MECHANISMS:
        path = OUT / f"{kind}.toml"
        text = example_text(kind)
        if args.check:
            if not path.exists() or path.read_text(encoding="utf-8") != text:
                stale.append(path.name)
        else:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path.relative_to(ROOT)}")
    if stale:
        print(f"out of date: {', '.join(stale)} (run python scripts/example_devices.py)")
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
