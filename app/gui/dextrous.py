"""The semi-dextrous region the workspace view shows: its requests and the job that answers them.

For a device with orientation freedoms (Stewart platform, Twin-Pantograph, Inoue platform) the
region is the positions of a 3D box where every orientation within +-angle can be held
(``metrics.dextrous``, paper 001 sec. V). The box is the one ``isoforce dextrous`` uses by
default: the preset's map range for x, y, z, a fixed position axis given the largest span of
the others. A coarse grid (``COARSE_POINTS`` per axis) follows the design at once; the full one
(``FULL_POINTS``, the command line's default) refines it. Plain Python, no Qt: the workspace
view runs ``run_region`` on a ``QtJobRunner`` of its own.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from kinematics.contract import Mechanism
from metrics.dextrous import DextrousRegion, box_grid, dextrous_region
from metrics.dextrous_orientations import orientation_set
from metrics.workspace import GridSpec

#: Points per axis of the region that follows a design change, and of the refined one.
COARSE_POINTS = 10
FULL_POINTS = 25
#: The orientation bound offered first, deg (paper 001's).
DEFAULT_ANGLE_DEG = 30.0
#: The scheduler tags: a coarse region is never cancelled by the refinement, only by a newer one.
COARSE_TAG = "dextrous-coarse"
FULL_TAG = "dextrous"
POSITION_AXES = ("x", "y", "z")


def has_region(mechanism: Mechanism) -> bool:
    """Whether ``mechanism`` has orientation freedoms to hold (and so a semi-dextrous region)."""
    try:
        orientation_set(mechanism, math.radians(DEFAULT_ANGLE_DEG))
    except ValueError:
        return False
    return True


def region_box(grid: GridSpec) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The position box (m) of a preset's map ``grid``: its x, y, z ranges, a fixed axis centred on its value
    with the largest span of the others (as ``isoforce dextrous`` without ``--box``).

    Raises
    ------
    ValueError
        When the map varies no position axis.
    """
    ranges = {a: (lo, hi) for a, lo, hi in zip(grid.axes, grid.lower, grid.upper) if a in POSITION_AXES}
    if not ranges:
        raise ValueError(f"the map varies no position axis (axes {grid.axes!r}): no box for a region")
    half = 0.5 * max(hi - lo for lo, hi in ranges.values())
    fixed = dict(grid.fixed)
    lower, upper = [], []
    for a in POSITION_AXES:
        lo, hi = ranges.get(a, (fixed.get(a, 0.0) - half, fixed.get(a, 0.0) + half))
        lower.append(float(lo))
        upper.append(float(hi))
    return tuple(lower), tuple(upper)


@dataclass(frozen=True)
class RegionRequest:
    """One semi-dextrous region to compute: ``mechanism`` over ``grid`` (``box_grid``) within ``angle`` rad."""

    mechanism: Mechanism
    grid: GridSpec
    angle: float
    stage: str = "full"          # "coarse" (a design change) or "full"
    tag: str = FULL_TAG
    generation: int = field(default=-1, compare=False)


def region_request(mechanism: Mechanism, map_grid: GridSpec, angle_deg: float, stage: str) -> RegionRequest:
    """The request for ``mechanism``'s region over its map's box, ``angle_deg`` deg, at ``stage``'s grid."""
    lower, upper = region_box(map_grid)
    points = COARSE_POINTS if stage == "coarse" else FULL_POINTS
    return RegionRequest(mechanism, box_grid(lower, upper, points), math.radians(float(angle_deg)), stage,
                         COARSE_TAG if stage == "coarse" else FULL_TAG)


def run_region(request: RegionRequest, progress: Callable[[float], None],
               cancelled: Callable[[], bool]) -> DextrousRegion:
    """The job: ``dextrous_region`` with ``orientation_set``'s default sampling (cancellable between calls)."""
    orientations = orientation_set(request.mechanism, request.angle)
    return dextrous_region(request.mechanism, request.grid, orientations, progress=progress, cancelled=cancelled)


def cm3(value_m3: float, digits: int = 4) -> str:
    """A volume in cm^3 as a person reads it: ``digits`` significant figures, no exponent for large ones.

    >>> cm3(3.046e-2), cm3(3.0e-6), cm3(3.4e-3, 2)
    ('30460', '3', '3400')
    """
    text = f"{value_m3 * 1e6:.{digits}g}"
    return f"{float(text):.0f}" if "e+" in text else text


def region_text(region: DextrousRegion, stage: str) -> str:
    """The label beside the surface: bound, volume (cm^3) with its grid error, the grid and its stage."""
    v = region.volume
    n = " x ".join(map(str, region.grid.resolution))
    text = (f"semi-dextrous region ±{math.degrees(region.orientations.angle):g} deg: "
            f"{cm3(v.value)} ± {cm3(v.error, 2)} cm^3\n({n} grid{', coarse' if stage == 'coarse' else ''}; "
            f"{region.orientations.count} orientations per point)")
    if not region.inside.any():
        text += "\nno grid point holds every orientation"
    if region.clipped:
        text += "\n(reaches the box: volume is a lower estimate)"
    return text
