"""One colour scale for one or several maps of a quantity, as plain data (no matplotlib).

A ``ColourScale`` says how a map's values become colours: a lookup table (``colour_maps``),
the limits and whether they are logarithmic or capped, or the classes of a categorical
quantity, and the colour bar's label. The app's painted map (``app.logic.map_picture``)
colours with it directly; the exported matplotlib figures (``app.plots.figures``) turn it into
a matplotlib colour map and norm. A comparison's panels share one scale, so equal values get
equal colours in all of them.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from app.logic.colour_limits import layers_limits, log_colours
from app.logic.colour_maps import colour_table
from app.logic.display_units import display_map
from metrics.bottleneck import BOTTLENECK_SHARED, BOTTLENECK_TIE
from metrics.quantities import QUANTITIES
from metrics.workspace import WorkspaceMap

#: Colour maps: sequential for magnitudes, diverging for differences, qualitative for classes.
SEQUENTIAL_CMAP = "viridis"
DIVERGING_CMAP = "RdBu_r"
CATEGORICAL_CMAP = "tab10"
#: Bottleneck codes that name no single actuator (``metrics.bottleneck``): tick label and colour,
#: neutral greys so that they read as "no one actuator" next to the actuators' tab10 colours.
#: ``BOTTLENECK_INFEASIBLE`` (-1) and any other negative code are drawn blank.
BOTTLENECK_CODES = {BOTTLENECK_TIE: ("tie", "#3f3f3f"), BOTTLENECK_SHARED: ("shared (redundant)", "#c7c7c7")}
#: Colours of the actuator classes: tab10 without its grey (the bottleneck codes' colours).
_CLASS_COLOURS = tuple(i for i in range(10) if i != 7)
#: The colour ranges of a plane of a 3D box map: the plane's own values, or the whole volume's.
COLOUR_RANGES = {"plane": "colours: this plane", "volume": "colours: whole volume"}


def hex_rgba(colour: str) -> tuple[float, float, float, float]:
    """``"#rrggbb"`` as RGBA floats in 0..1 (as ``matplotlib.colors.to_rgba`` reads it).

    >>> hex_rgba("#ff8000")
    (1.0, 0.5019607843137255, 0.0, 1.0)
    """
    raw = bytes.fromhex(colour.lstrip("#"))
    return (raw[0] / 255, raw[1] / 255, raw[2] / 255, 1.0)


@dataclass(frozen=True, eq=False)
class ColourScale:
    """How values become colours, and the colour bar that says so.

    ``lut`` (N, 4) RGBA floats is the colour of each index; a continuous value ``x`` takes index
    ``int(N (x - lo) / (hi - lo))`` clipped to ``[0, N - 1]`` (on ``log10`` of everything for a
    ``log`` scale), exactly as a matplotlib colour map under ``Normalize`` or ``LogNorm``; a
    class takes its index. ``to_data(values, feasible)`` gives the masked array to colour
    (values, or class indices), blank where infeasible or not a number.

    ``kind`` tells maps that can share one image and colour bar; ``bar_key`` what the colour
    bar shows (it is redrawn when this changes); ``limits`` the ``(lo, hi)`` of a continuous or
    difference scale (None for classes); ``capped`` whether the top colour also stands for
    everything above ``hi``; ``tick_labels`` the classes' names on the bar.
    """

    kind: tuple
    lut: np.ndarray
    to_data: Callable
    label: str
    bar_key: tuple
    limits: tuple[float, float] | None = None
    log: bool = False
    capped: bool = False
    tick_labels: tuple[str, ...] = ()

    @property
    def categorical(self) -> bool:
        """Whether the scale colours classes rather than values."""
        return self.kind[0] == "categorical"

    @property
    def lut_bytes(self) -> np.ndarray:
        """The table as RGBA bytes, shape (N, 4): ``cmap(index, bytes=True)``'s rounding."""
        return (self.lut * 255).astype(np.uint8)

    def colours(self, values: np.ndarray, blank: np.ndarray) -> np.ndarray:
        """RGBA bytes (..., 4) of plain ``values`` (or class indices), transparent where ``blank``.

        Parameters
        ----------
        values : ndarray, shape (...)
        blank : ndarray of bool, shape (...)

        Returns
        -------
        ndarray of uint8, shape (..., 4)
        """
        n = len(self.lut)
        lut32 = np.ascontiguousarray(self.lut_bytes).view(np.uint32).ravel()
        if self.categorical:
            index = np.clip(values, 0, n - 1).astype(np.intp)
        else:
            # Normalize's arithmetic ((x - vmin) / (vmax - vmin), on log10 for LogNorm), then the
            # colour map's index int(x N) clipped to [0, N - 1]: its under and over colours are the ends.
            x = np.asarray(values, float)
            lo, hi = self.limits
            if self.log:
                blank = blank | ~(x > 0)
                with np.errstate(divide="ignore", invalid="ignore"):
                    x = np.log10(np.where(x > 0, x, 1.0))
                lo, hi = np.log10(lo), np.log10(hi)
            x = (x - lo) / (hi - lo)
            blank = blank | np.isnan(x)
            x *= n
            np.clip(x, 0, n - 1, out=x)
            with np.errstate(invalid="ignore"):
                index = x.astype(np.intp)      # (garbage where nan: blank, zeroed below)
        # (A boolean-mask assignment costs several times these: index clipped, colour times "shown".)
        out = lut32.take(index, mode="clip")
        out *= ~blank
        return out.view(np.uint8).reshape(*np.shape(values), 4)

    def with_note(self, note: str) -> ColourScale:
        """This scale with ``note`` on a line of its own under the colour bar's label, e.g. which
        colour range a plane of a volume is drawn with (``COLOUR_RANGES``)."""
        return replace(self, label=f"{self.label}\n{note}", bar_key=(self.bar_key, note))


def _masked(values, feasible) -> np.ma.MaskedArray:
    return np.ma.masked_array(values, mask=~(feasible & np.isfinite(values)))


def colour_scale(quantity: str, preset_or_title, layers, *, difference: bool = False,
                 limits: tuple[float, float, bool] | None = None) -> ColourScale:
    """One colour scale for one or several maps of ``quantity`` (a comparison shares one).

    Parameters
    ----------
    quantity : str
        A scalar quantity of ``metrics.quantities.QUANTITIES``.
    preset_or_title : resources.Preset or str
        A preset names the bottleneck's classes (its actuators).
    layers : sequence of (values, feasible)
        Each map's values and feasibility mask, arrays of one map's shape (nx, ny); the
        limits (or classes) cover every layer, so equal values get equal colours in all.
    difference : bool
        The values are a difference of two maps: a diverging scale centred at zero.
    limits : tuple, optional
        ``(lo, hi, capped)`` of a continuous quantity's layers, computed beforehand
        (``map_colour_limits``); default computed here.

    Returns
    -------
    ColourScale
    """
    layers = [(np.asarray(v), np.asarray(f, bool)) for v, f in layers]
    if not layers:
        raise ValueError("layers must hold at least one (values, feasible) pair, got none")
    if difference:
        return _difference_scale(layers, quantity)
    if QUANTITIES[quantity].categorical:
        return _categorical_scale(layers, quantity, preset_or_title)
    return _continuous_scale(layers, quantity, limits)


def plane_scale(volume: WorkspaceMap, plane: WorkspaceMap, quantity: str, preset_or_title,
                colour_range: str = "plane") -> ColourScale | None:
    """The colour scale a plane of a 3D box map is drawn with, in the display unit, its range named.

    Parameters
    ----------
    volume : WorkspaceMap
        The 3D box map (arrays (nx, ny, nz)).
    plane : WorkspaceMap
        One plane of it (``app.logic.planes.volume_slice``; arrays (n_a, n_b)).
    quantity : str
        A scalar quantity both hold.
    preset_or_title : resources.Preset or str
        As for ``colour_scale``.
    colour_range : {"plane", "volume"}
        Span the plane's feasible values (a plane of 2-7 N is not one colour in a volume of
        0-18 N), or the whole volume's (planes compared with each other as the slider moves).

    Returns
    -------
    ColourScale or None
        Its bar says which range (``COLOUR_RANGES``); None for a categorical quantity (its
        classes have no range).
    """
    if colour_range not in COLOUR_RANGES:
        raise ValueError(f"colour_range must be one of {', '.join(COLOUR_RANGES)}, got {colour_range!r}")
    if QUANTITIES[quantity].categorical:
        return None
    source = volume if colour_range == "volume" else plane
    shown = display_map(source, quantity)
    scale = colour_scale(quantity, preset_or_title, [(shown.values[quantity], shown.feasible)])
    return scale.with_note(COLOUR_RANGES[colour_range])


# Each ``_*_scale`` says how maps are coloured (see ``colour_scale``).
def _difference_scale(layers, quantity) -> ColourScale:
    """A difference of two maps on a diverging scale centred at zero."""
    node = QUANTITIES[quantity]
    shown = [f & np.isfinite(v) for v, f in layers]
    spans = [float(np.max(np.abs(v[s]))) for (v, _), s in zip(layers, shown) if np.any(s)]
    span = max(spans) if spans else 1.0
    clim = (-span or -1.0, span or 1.0)
    label = f"change of {node.label.lower()}" + (f" ({node.unit})" if node.unit else "")
    return ColourScale(kind=("difference", quantity), lut=colour_table(DIVERGING_CMAP), to_data=_masked,
                       label=label, bar_key=(clim, label), limits=clim)


def _continuous_scale(layers, quantity, limits=None) -> ColourScale:
    """Sequential colours; log scale for the condition number; capped at ``colour_limits``
    (``limits``, when the caller has them: ``map_colour_limits`` of the one layer)."""
    node = QUANTITIES[quantity]
    log = log_colours(quantity)
    lo, hi, capped = limits if limits is not None else layers_limits(layers, log=log)
    # The cap on a line of its own: one line as long as both was taller than a flat map's bar.
    label = node.label + (f" ({node.unit})" if node.unit else "") + (f"\ncolours capped at {hi:.3g}" if capped else "")
    return ColourScale(kind=("continuous", quantity, log, capped), lut=colour_table(SEQUENTIAL_CMAP),
                       to_data=_masked, label=label, bar_key=(lo, hi, label), limits=(lo, hi), log=log,
                       capped=bool(capped))


def category_names(quantity: str, preset_or_title) -> tuple[str, ...]:
    """Tick labels of a categorical quantity: actuator names for the bottleneck, the model's
    classes for singularity (``singularity_classes``); none without a mechanism (codes by number)."""
    mechanism = getattr(preset_or_title, "mechanism", None)
    if mechanism is None:
        return ()
    return tuple(mechanism.singularity_classes if quantity == "singularity" else mechanism.joint_names)


def category_classes(quantity: str, preset_or_title, codes) -> list[tuple[int, str, tuple]]:
    """The classes a categorical map draws: ``(code, tick label, RGBA colour)`` in colour-bar order.

    Every actuator (or singularity class) by name, then any larger code found by number, then
    the bottleneck's "tie" and "shared (redundant)" codes where they occur (``codes``: the codes
    found at feasible points). Other negative codes (``-1``, infeasible) have no class: blank.
    """
    codes = np.unique(np.asarray(codes, np.int64))
    names = list(category_names(quantity, preset_or_title))
    top = int(codes.max()) + 1 if codes.size and codes.max() >= 0 else 0
    names += [str(i) for i in range(len(names), top)]
    palette = colour_table(CATEGORICAL_CMAP)
    classes = [(i, name, tuple(palette[_CLASS_COLOURS[i % len(_CLASS_COLOURS)]])) for i, name in enumerate(names)]
    if quantity == "bottleneck":
        classes += [(code, label, hex_rgba(colour)) for code, (label, colour) in BOTTLENECK_CODES.items()
                    if code in codes]
    return classes


def _categorical_scale(layers, quantity, preset_or_title) -> ColourScale:
    """One colour per class (bottleneck actuator, tie, shared; singularity class), ticks labelled by name."""
    found = [np.asarray(v[f]).astype(np.int64) for v, f in layers]
    classes = category_classes(quantity, preset_or_title, np.concatenate(found))
    if not classes:                 # no names and nothing feasible: one placeholder class
        classes = [(0, "0", tuple(colour_table(CATEGORICAL_CMAP)[0]))]
    code_of = np.array([code for code, _, _ in classes], np.int64)
    names = tuple(name for _, name, _ in classes)
    # Counts next to the names: singular classes and ties cover a few grid points, too few to
    # see; with several maps sharing the bar, one count per map ("reference / current").
    counts = [[int(np.count_nonzero(codes == code)) for codes in found] for code in code_of]
    labels = tuple(f"{name} ({' / '.join(map(str, c))})" for name, c in zip(names, counts))

    def to_data(values, feasible):
        """Class index per point (position in the colour bar), masked off the classes."""
        values = np.asarray(values).astype(np.int64)
        index = np.full(values.shape, -1, np.int64)
        for k_class, code in enumerate(code_of):
            index[values == code] = k_class
        return np.ma.masked_array(index, mask=~(np.asarray(feasible, bool) & (index >= 0)))

    bar_label = QUANTITIES[quantity].label + (" (points per panel, left to right)" if len(layers) > 1 else "")
    return ColourScale(kind=("categorical", quantity, names), lut=np.array([c for _, _, c in classes], float),
                       to_data=to_data, label=bar_label, bar_key=labels, tick_labels=labels)
