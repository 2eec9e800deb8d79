"""``isoforce show DEVICE``: every parameter (name, unit, value), the ratings, the default map and pose.

The names are the ones ``--set`` takes; values are in their display units. The torque
ratings (joint side, continuous and peak, ``null`` where the source gives none) and whether
the model has a mass model (so ``--gravity``) are listed too.
"""
from __future__ import annotations

import argparse
from typing import Any

from app.cli._args import add_device_argument, load_device
from app.cli._format import describe_grid, number, point_text, print_json, table


def register(subparsers) -> None:
    p = subparsers.add_parser("show", help="every parameter of a device with its unit and value",
                              description="Print every parameter of a device (name, unit, value), its default "
                                          "map and pose. The names are the ones --set takes.")
    add_device_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def ratings(mechanism) -> dict[str, Any]:
    """The joint-side torque ratings (N m; N for prismatic joints) and the gravity model, JSON-ready.

    ``continuous`` and ``peak`` (``None``: no peak rating), ``joint_names``, ``unit``, and
    ``gravity_model`` (``--gravity`` is accepted) with the ``mountings`` it takes.
    """
    from kinematics.gravity import MOUNTINGS

    units = ["N" if u == "m" else "N m" for u in mechanism.joint_units]
    peak = mechanism.peak_torque_limits()
    return {"joint_names": list(mechanism.joint_names), "unit": units[0] if len(set(units)) == 1 else units,
            "continuous": [float(v) for v in mechanism.torque_limits()],
            "peak": None if peak is None else [float(v) for v in peak],
            "gravity_model": bool(mechanism.has_mass_model),
            "mountings": list(MOUNTINGS) if mechanism.has_mass_model else []}


def device_description(preset) -> dict[str, Any]:
    """A preset as a JSON-ready dict: parameters in display units, ratings, default map and pose in mm."""
    params = []
    for info, value in preset.mechanism.parameter_table():
        entry: dict[str, Any] = {"name": info.name, "unit": info.unit,
                                 "value": list(value) if isinstance(value, tuple) else value,
                                 "description": info.description}
        if info.labels:
            entry["labels"] = list(info.labels)
        if info.choices:
            entry["choices"] = list(info.choices)
        params.append(entry)
    grid = preset.grid
    return {
        "device": preset.key, "name": preset.name, "mechanism": preset.kind,
        "description": preset.description, "source": preset.source,
        "task_names": list(preset.mechanism.task_names), "joint_names": list(preset.mechanism.joint_names),
        "parameters": params,
        "ratings": ratings(preset.mechanism),
        "map": {"axes": list(grid.axes), "lower": [v * 1e3 for v in grid.lower],
                "upper": [v * 1e3 for v in grid.upper], "resolution": list(grid.resolution),
                "fixed": {n: v * 1e3 for n, v in grid.fixed}},
        "pose": [v * 1e3 for v in preset.pose] if preset.pose is not None else None,
        "provenance": {key: list(value) if isinstance(value, tuple) else value for key, value in preset.provenance},
    }


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    info = device_description(preset)
    if args.json:
        print_json(info)
        return 0
    print(f"{preset.name} ({preset.key}, {preset.kind})")
    if preset.description:
        print(preset.description)
    rows = [("parameter", "unit", "value")]
    for p in info["parameters"]:
        if "labels" in p:
            value = ", ".join(f"{lab} = {number(v)}" for lab, v in zip(p["labels"], p["value"]))
        elif isinstance(p["value"], str):
            value = p["value"]
        else:
            value = number(p["value"])
        changed = f"changed.{p['name']}" in info["provenance"]
        rows.append((p["name"], p["unit"] or "-", value + ("  (changed: see source)" if changed else "")))
    print()
    print(table(rows))
    print()
    r = info["ratings"]
    units = r["unit"] if isinstance(r["unit"], list) else [r["unit"]] * len(r["joint_names"])

    def limits(values) -> str:
        return ", ".join(f"{n} = {number(v)} {u}" for n, v, u in zip(r["joint_names"], values, units))

    print(f"torque rating, continuous (joint side, --rating continuous): {limits(r['continuous'])}")
    print("torque rating, peak (--rating peak): "
          + (limits(r["peak"]) if r["peak"] is not None else "none (the source gives one torque per actuator)"))
    print("gravity model: " + ("link masses and centres of mass (--gravity " + "|".join(r["mountings"])
                               + "|GX,GY,GZ)" if r["gravity_model"] else "none (no link masses: no --gravity)"))
    print()
    print(f"default map: {describe_grid(preset.grid, preset.mechanism)}")
    if preset.pose is not None:
        print(f"default pose: {point_text(preset.mechanism, preset.pose)}")
    if preset.provenance:
        # Where each number comes from, and which are estimates (the preset's [source] table).
        print()
        print("source:")
        for key, value in preset.provenance:
            text = ", ".join(map(str, value)) if isinstance(value, tuple) else str(value)
            print(f"  {key}: {text if text else '-'}")
    return 0
