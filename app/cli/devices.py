"""``isoforce devices``: the shipped device presets, one line each."""
from __future__ import annotations

import argparse

from app.cli._format import print_json, table


def register(subparsers) -> None:
    p = subparsers.add_parser("devices", help="list the shipped device presets",
                              description="List the shipped device presets.")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from resources import list_presets, load_preset

    presets = [load_preset(key) for key in list_presets()]
    if args.json:
        print_json({"devices": [{"key": p.key, "name": p.name, "mechanism": p.kind,
                                 "description": p.description} for p in presets]})
        return 0
    print(table([("key", "mechanism", "name")] + [(p.key, p.kind, p.name) for p in presets]))
    return 0
