"""``isoforce figure``: the app's own views rendered off-screen, with no display.

``--view map`` heat map, ``pose`` the 3D pose with its force glyphs, ``workspace`` the 3D
workspace, ``compare`` the preset's own design (reference) against the design with the
``--set`` changes (current). PNG/SVG/PDF by the suffix of ``--out``.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from metrics.quantities import CORE_QUANTITIES, check_quantities
from metrics.workspace import compute_map

from ..export import FIGURE_SUFFIXES, check_output
from ..glyphs import DEFAULT_GLYPHS, GLYPHS
from ..render import VIEWS, export_view, parse_size
from ._args import (
    UsageError,
    add_device_argument,
    add_resolution_argument,
    check_memory,
    device_grid,
    load_device,
    parse_point,
)
from .pose import check_pose


def _glyphs(text: str | None) -> frozenset[str]:
    if text is None:
        return DEFAULT_GLYPHS
    names = frozenset(t.strip() for t in text.split(",") if t.strip())
    unknown = sorted(names - set(GLYPHS))
    if unknown:
        raise UsageError(f"--glyphs: unknown glyph {unknown[0]!r}; known: {', '.join(GLYPHS)}")
    return names


def _force(text: str, m: int) -> tuple[float, ...]:
    """``"FX,FY,FZ"`` in N, or a UsageError naming --force."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != m:
        raise UsageError(f"--force needs {m} comma-separated numbers in N, got {text!r}")
    return values


def run(args: argparse.Namespace) -> int:
    preset = load_device(args)
    mech = preset.mechanism
    try:
        target = check_output(args.out, FIGURE_SUFFIXES, "--out")
        size = parse_size(args.size) if args.size else None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    quantity = args.quantity
    try:
        check_quantities(mech, [quantity])
    except ValueError as exc:
        raise UsageError(f"--quantity: {exc}") from None
    pose = tuple(parse_point(args.at, mech)) if args.at else preset.pose
    if args.view == "pose":
        if pose is None:
            raise UsageError(f"--at is required: preset {preset.key!r} has no default pose")
        check_pose(preset, np.asarray(pose, float), from_preset=not args.at)     # exit 2 like `pose`
    desired = _force(args.force, mech.task_dim) if args.force else None
    glyphs = _glyphs(args.glyphs)
    grid = device_grid(preset, args.resolution)
    needed = tuple(sorted(set(CORE_QUANTITIES) | {quantity}))
    if args.view != "pose":
        check_memory(mech, grid, needed, output="figure", copies=2 if args.view == "compare" else 1)
    wmap = compute_map(mech, grid, needed) if args.view != "pose" else None
    reference_map = None
    if args.view == "compare":
        from resources import load_preset
        original = load_preset(args.device).mechanism
        reference_map = compute_map(original, grid, needed)
    try:
        export_view(args.view, target, preset=preset, mechanism=mech, workspace_map=wmap, quantity=quantity,
                    pose=pose, glyphs=glyphs, desired_force=desired, reference_map=reference_map, size=size,
                    compare_mode=args.compare)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(f"wrote {target}", file=sys.stderr)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("figure", help="render one of the app's views to PNG/SVG/PDF, headless",
                              description=__doc__.split("\n\n")[0])
    add_device_argument(p)
    p.add_argument("--view", choices=VIEWS, default="map", help="which view (default: map)")
    p.add_argument("--quantity", default="isotropic_force", help="map quantity (default: isotropic_force)")
    p.add_argument("--at", metavar="X,Y,Z", help="pose in mm for the pose view (default: the preset's)")
    p.add_argument("--force", metavar="FX,FY,FZ", help="desired force in N, drawn with its clamped version")
    p.add_argument("--glyphs", metavar="NAMES", help=f"comma-separated glyphs to draw ({', '.join(GLYPHS)})")
    p.add_argument("--compare", choices=("side", "difference"), default="side",
                   help="compare view: side by side or current - reference")
    p.add_argument("--size", metavar="WxH", help="PNG size in pixels (default 1600x1200 for 3D views)")
    add_resolution_argument(p)
    p.add_argument("--out", required=True, help="output file: .png, .svg or .pdf")
    p.set_defaults(func=run)
