"""Parameter sweeps of a device's global figures, and the five-bar link-length sweep.

* **Scenarios and gear ratios.** ``scenario_maps`` computes a device's core quantities
  (condition number, maximum anisotropic and maximum isotropic force) over a grid for each of
  several ``(mechanism, grid)`` scenarios, e.g. the same device with different gear ratios;
  ``isotropic_force_by_gear_ratio`` gives the isotropic-force statistics of an Inverse3 against
  its base gear ratio; ``inverse3_isotropic_sup`` bounds the largest isotropic force any
  feasible pose of an Inverse3's ``theta_0 = 0`` slice can hold, however fine the grid.
  Loading presets is the caller's job: ``metrics`` does not import ``resources``.
* **Link-length sweep of a planar five-bar**, scored by the number of workspace samples
  whose condition number exceeds a threshold (the performance measure of Singh, Saha and
  Manivannan, docs/references.md). The count depends on how the workspace is sampled:
  ``SAMPLINGS`` holds four samplings, each documented exactly, ``link_length_sweep`` runs a
  sweep under any of them, and ``kendall_tau`` and ``SweepResult.top`` show how far the
  ranking depends on the choice.

The papers' printed tables and the comparisons with them live with the reproduction
(``scripts/paper_data.py``, ``scripts/reproduce_papers.py``). Lengths are in metres, angles
in radians, as everywhere in the compute layer.
"""
from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from kinematics import mechanism_class
from kinematics.arrays import FloatArray
from kinematics.contract import Mechanism

from .quantities import CORE_QUANTITIES, evaluate
from .workspace import GridSpec, Stats, WorkspaceMap, compute_map

# ------------------------------------------------------------------------------------------
# Scenarios and gear ratios
# ------------------------------------------------------------------------------------------


def scenario_maps(cases: Sequence[tuple[Mechanism, GridSpec]], *,
                  quantities: Sequence[str] = CORE_QUANTITIES,
                  resolution: int | tuple[int, int] | None = None) -> list[WorkspaceMap]:
    """One map of ``quantities`` for each ``(mechanism, grid)`` scenario.

    Parameters
    ----------
    cases : sequence of (Mechanism, GridSpec)
        The scenarios, e.g. presets' mechanisms with their default maps.
    quantities : sequence of str
        Quantities to map; the default is the device's core quantities (condition number,
        maximum anisotropic and maximum isotropic force).
    resolution : int or (int, int), optional
        Overrides every grid's resolution.

    Returns
    -------
    list of WorkspaceMap
        One per case, in order; their ``stats`` are the scenarios' global figures.
    """
    out = []
    for mech, grid in cases:
        grid = grid if resolution is None else grid.with_resolution(resolution)
        out.append(compute_map(mech, grid, tuple(quantities)))
    return out


@dataclass(frozen=True)
class GearRatioStats:
    """Isotropic-force statistics of a map for one base gear ratio ``g1`` (the other ratios unchanged)."""

    g1: float
    isotropic: Stats


def isotropic_force_by_gear_ratio(mech: Mechanism, grid: GridSpec,
                                  g1_values: Sequence[float]) -> list[GearRatioStats]:
    """Isotropic force against the base gear ratio: the map's statistics for each ``g1``.

    Parameters
    ----------
    mech : Inverse3
        The device; its five-bar gear ratios ``g2, g3`` are kept.
    grid : GridSpec
        The map, e.g. the preset's default.
    g1_values : sequence of float
        Base gear ratios ``g1`` to try, shape (k,).

    Returns
    -------
    list of GearRatioStats
        One per ``g1``, in order: ``Stats`` of ``isotropic_force`` over ``grid``.
    """
    g = mech.params.gear_ratios
    out = []
    for g1 in g1_values:
        changed = mech.replace(gear_ratios=(float(g1), g[1], g[2]))
        out.append(GearRatioStats(float(g1), compute_map(changed, grid, ("isotropic_force",)).stats["isotropic_force"]))
    return out


@dataclass(frozen=True)
class IsotropicSup:
    """Upper bound on the isotropic force over an Inverse3 slice, by half-spread ``h``.

    For every feasible pose on the ``theta_0 = 0`` slice with link half-spread ``h`` and
    ``theta_3 >= 0``: ``isotropic <= bound(h) = min(five-bar facet(h), base facet at
    x_min(h))``. ``sup`` is ``max_h bound(h)`` over the sampled ``h``; ``corner`` is the pose
    where the maximum is attained, ``corner_value`` its exact isotropic force.
    """

    h: FloatArray                 # (k,) half-spreads sampled, rad
    five_bar_facet: FloatArray    # (k,) N
    x_min: FloatArray             # (k,) m
    bound: FloatArray             # (k,) N
    sup: float
    h_at_sup: float
    corner: FloatArray            # (3,) joints (theta_0, theta_p1, theta_p2) of the maximiser
    corner_point: FloatArray      # (3,) m
    corner_value: float


def inverse3_isotropic_sup(mech: Mechanism, *, samples: int = 20001) -> IsotropicSup:
    """The largest isotropic force any feasible pose of the ``theta_0 = 0`` slice can hold.

    On the slice ``x`` is the radial coordinate and ``u = x``, so (DESIGN.md, the stable
    formula) ``isotropic = min(t0 / sqrt(x^2 + c^2), t_p / |J[:, p1]|, t_p / |J[:, p2]|)`` with
    ``c`` the plane offset. Both five-bar columns have the norm ``sqrt(a3^2 + a3'(h)^2) / 2``
    (the ``theta_3`` and ``h`` directions are orthogonal), a function of the half-spread
    ``h = (theta_p1 - theta_p2) / 2`` only. For each ``h`` the joint limits bound
    ``theta_3 = theta_p1 - h - 90 deg`` from above by ``upper_p1 - h - 90 deg`` (and
    ``upper_p2 + h - 90 deg``); on ``0 <= theta_3 <= 90 deg`` the radial coordinate
    ``x = a3 cos theta_3`` is smallest, and the base facet largest, at that upper end. Poses
    with ``theta_3 < 0`` lie below the five-bar centre and are covered by the caller's own
    argument (for the Inverse3 the body constraint forces them to ``x > 65 mm`` or to
    ``theta_3 > -asin((base_height - body_height) / a3)``; see the tests).

    Only valid while the upper ``theta_3`` end stays within ``[0, 90 deg]``; entries where
    it does not get ``nan``.

    Parameters
    ----------
    mech : Inverse3
        The device (link lengths, joint limits, torque limits).
    samples : int
        Half-spreads ``h`` sampled evenly between the link-spread limits.

    Returns
    -------
    IsotropicSup
        The bound per ``h``, arrays of shape (samples,); its maximum (N) and the pose attaining it.
    """
    p = mech.params
    h = np.linspace(p.min_link_spread / 2.0, p.max_link_spread / 2.0, samples)
    l1, l2 = p.proximal_length, p.distal_length
    root = np.sqrt(l2 * l2 - (l1 * np.sin(h)) ** 2)
    a3 = l1 * np.cos(h) + root
    da3 = -l1 * np.sin(h) * (1.0 + l1 * np.cos(h) / root)
    t = mech.torque_limits()
    five_bar = np.minimum(t[1], t[2]) / (0.5 * np.sqrt(a3 * a3 + da3 * da3))
    quarter = np.pi / 2.0
    th3_hi = np.minimum(p.upper_limits[1] - h - quarter, p.upper_limits[2] + h - quarter)
    valid = (th3_hi >= 0.0) & (th3_hi <= quarter)
    x_min = np.where(valid, a3 * np.cos(th3_hi), np.nan)
    base = t[0] / np.hypot(x_min, p.plane_offset)
    bound = np.where(valid, np.minimum(five_bar, base), np.nan)
    i = int(np.nanargmax(bound))
    th3 = th3_hi[i]
    corner = np.array([0.0, th3 + h[i] + quarter, th3 - h[i] + quarter])
    point, _ = mech.forward(corner)
    value = float(np.min(t / np.linalg.norm(mech.jacobian(corner), axis=0)))
    return IsotropicSup(h, five_bar, x_min, bound, float(bound[i]), float(h[i]), corner, point, value)


# ------------------------------------------------------------------------------------------
# Link-length sweep of a planar five-bar
# ------------------------------------------------------------------------------------------

#: Default condition-number threshold of the count ("points with K > 5", Singh et al.).
ILL_CONDITIONED = 5.0


def link_length_designs(a1: Sequence[float], a2: Sequence[float], a3: Sequence[float]) -> FloatArray:
    """Every combination of the link lengths (m), shape (k, 3): ``a1`` slowest, ``a3`` fastest.

    Parameters
    ----------
    a1, a2, a3 : sequence of float
        Proximal lengths, distal lengths and base half-widths to combine, in metres.

    Returns
    -------
    ndarray, shape (len(a1) * len(a2) * len(a3), 3)
        One design ``(a1, a2, a3)`` per row.
    """
    return np.array(list(itertools.product(a1, a2, a3)), dtype=float)


def _centres(lo: float, hi: float, step: float) -> FloatArray:
    """Cell centres of ``[lo, hi]`` cut into ``round((hi - lo) / step)`` equal cells."""
    n = int(round((hi - lo) / step))
    return lo + (np.arange(n) + 0.5) * ((hi - lo) / n)


@dataclass(frozen=True)
class Sampling:
    """How a design's workspace is sampled for the "points with K > 5" count.

    Singh, Saha and Manivannan (docs/references.md) say only that the workspace "is divided
    in a set of circular arcs"; these are the readings we compare.

    ``kind``:
      ``"grid"``: cell centres of a uniform grid over the box ``x in box[0]``,
      ``y in box[1]``, cells of side ``step`` (the box is cut into a whole number of cells).
      ``"arcs"``: circular arcs about the midpoint ``O`` of the base joints; radii at the
      centres of ``step``-wide rings from 0 to the outer reach ``a1 + a2 + a3`` (in the
      frame's units), each arc sampled at the centres of ``arc_points`` equal angular cells
      of ``[0, pi]``. Every arc has the same number of points, so the point density falls as
      ``1 / radius``: the "set of circular arcs" read literally.
    ``frame``:
      ``"physical"``: the design in metres; the count grows with the workspace.
      ``"normalised"``: the normalised lengths ``r_i = a_i / L`` with
      ``L = (a1 + a2 + a3) / 3`` (Singh et al., sec. 3); since ``r1 + r2 + r3 = 3``, every
      design fits the box ``[-3, 3] x [0, 3]``
      and the count depends on the design's shape only (the condition number is
      scale-invariant).
    Only the upper half plane is sampled: the working mode puts the end-effector there.
    """

    name: str
    kind: str
    frame: str
    step: float
    box: tuple[tuple[float, float], tuple[float, float]] | None = None
    arc_points: int = 0
    description: str = ""

    def __post_init__(self) -> None:
        if self.kind not in ("grid", "arcs"):
            raise ValueError(f"kind must be 'grid' or 'arcs', got {self.kind!r}")
        if self.frame not in ("physical", "normalised"):
            raise ValueError(f"frame must be 'physical' or 'normalised', got {self.frame!r}")
        if not (math.isfinite(self.step) and self.step > 0):
            raise ValueError(f"step must be a positive finite number, got {self.step!r}")
        if self.kind == "grid" and self.box is None:
            raise ValueError("a 'grid' sampling needs box=((xlo, xhi), (ylo, yhi))")
        if self.kind == "arcs" and self.arc_points < 1:
            raise ValueError(f"an 'arcs' sampling needs arc_points >= 1, got {self.arc_points!r}")

    def scale(self, design: ArrayLike) -> float:
        """Length unit of the sampling frame for ``design``: 1 (m) or ``L``.

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m.

        Returns
        -------
        float
            In m.

        Examples
        --------
        >>> round(SAMPLINGS["normalised"].scale((0.1, 0.2, 0.3)), 9), SAMPLINGS["grid"].scale((0.1, 0.2, 0.3))
        (0.2, 1.0)
        """
        a1, a2, a3 = (float(v) for v in design)
        return 1.0 if self.frame == "physical" else (a1 + a2 + a3) / 3.0

    def points(self, design: ArrayLike) -> FloatArray:
        """Sample points for ``design = (a1, a2, a3)`` in the frame's units, shape (N, 2).

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m.

        Returns
        -------
        ndarray, shape (N, 2)
            Points ``(x, y)`` in m (physical frame) or in units of ``L`` (normalised).

        Examples
        --------
        >>> SAMPLINGS["grid"].points((0.1, 0.1, 0.05)).shape
        (43200, 2)
        """
        a1, a2, a3 = (float(v) for v in design)
        s = self.scale(design)
        if self.kind == "grid":
            (xlo, xhi), (ylo, yhi) = self.box
            x, y = np.meshgrid(_centres(xlo, xhi, self.step), _centres(ylo, yhi, self.step), indexing="ij")
            return np.stack([x.ravel(), y.ravel()], axis=-1)
        reach = (a1 + a2 + a3) / s
        radii = _centres(0.0, self.step * math.ceil(reach / self.step - 1e-9), self.step)
        angles = _centres(0.0, np.pi, np.pi / self.arc_points)
        r, phi = np.meshgrid(radii, angles, indexing="ij")
        return np.stack([(r * np.cos(phi)).ravel(), (r * np.sin(phi)).ravel()], axis=-1)

    def mechanism(self, design: ArrayLike, working_mode: str = "+-") -> Mechanism:
        """The five-bar of ``design`` in this frame's units (normalised: lengths ``r_i``).

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m.
        working_mode : str
            The five-bar's working mode.

        Returns
        -------
        FiveBar
        """
        s = self.scale(design)
        lengths = dict(zip(DESIGN_PARAMETERS, (float(v) / s for v in design)))
        return mechanism_class("fivebar")(**lengths, working_mode=working_mode)


#: The parameters a sampling's ``design = (a1, a2, a3)`` names, and the task coordinates of its
#: points: the five-bar's. A study's mechanism needs both to be sampled this way.
DESIGN_PARAMETERS = ("proximal", "distal", "half_base")
SAMPLED_TASK = ("x", "y")


#: Four samplings of a five-bar's workspace (docs/reproduction.md compares them). The physical
#: boxes hold every design with a1 + a2 + a3 <= 0.32 m and a1 + a2 <= 0.27 m.
SAMPLINGS: dict[str, Sampling] = {s.name: s for s in (
    Sampling("grid", "grid", "physical", 0.002, box=((-0.32, 0.32), (0.0, 0.27)),
             description="uniform 2 mm grid (cell centres) over the fixed box x in [-320, 320] mm, "
                         "y in [0, 270] mm: 320 x 135 = 43,200 points for every design"),
    Sampling("arcs", "arcs", "physical", 0.002, arc_points=180,
             description="arcs about O every 2 mm of radius (ring centres) out to a1 + a2 + a3, "
                         "180 points per arc at 0.5, 1.5, ..., 179.5 deg"),
    Sampling("normalised", "grid", "normalised", 0.02, box=((-3.0, 3.0), (0.0, 3.0)),
             description="uniform grid (cell centres) of step 0.02 L over [-3, 3] x [0, 3] in normalised "
                         "lengths r_i = a_i / L, L = (a1 + a2 + a3) / 3: 300 x 150 = 45,000 points"),
    Sampling("normalised_arcs", "arcs", "normalised", 0.02, arc_points=180,
             description="arcs about O every 0.02 L of radius out to r1 + r2 + r3 = 3, 180 points per arc "
                         "at 0.5, ..., 179.5 deg: 150 x 180 = 27,000 points for every design"),
)}


@dataclass(frozen=True)
class DesignCount:
    """The sweep's measure for one design: how many samples are reachable and ill-conditioned."""

    design: tuple[float, float, float]
    samples: int
    reachable: int
    ill: int          # condition number > threshold (inf included)
    singular: int     # condition number inf


def count_ill_conditioned(design: ArrayLike, sampling: Sampling, *, working_mode: str = "+-",
                          threshold: float = ILL_CONDITIONED) -> DesignCount:
    """Count the samples of ``design``'s workspace with condition number above ``threshold``.

    A sample counts when the inverse kinematics reaches it in ``working_mode`` and
    ``cond(J) > threshold``, a singular J (``cond = inf``) included. Unreachable samples are
    not part of the workspace and do not count.

    Parameters
    ----------
    design : array_like, shape (3,)
        Link lengths ``(a1, a2, a3)``, m.
    sampling : Sampling
        How the workspace is sampled.
    working_mode : str
        The five-bar's working mode.
    threshold : float
        Condition-number threshold (dimensionless).

    Returns
    -------
    DesignCount

    Examples
    --------
    >>> count_ill_conditioned((0.1, 0.1, 0.05), SAMPLINGS["normalised_arcs"]).samples
    27000
    """
    mech = sampling.mechanism(design, working_mode)
    pts = sampling.points(design)
    ev = evaluate(mech, pts, ("condition_number",))
    k = ev.values["condition_number"][ev.feasible]
    return DesignCount(tuple(float(v) for v in design), int(pts.shape[0]), int(ev.feasible.sum()),
                       int(np.count_nonzero(k > threshold)), int(np.count_nonzero(np.isinf(k))))


@dataclass(frozen=True)
class SweepResult:
    """Counts for every design of a sweep under one sampling and working mode."""

    sampling: Sampling
    working_mode: str
    designs: FloatArray                     # (k, 3) m
    counts: np.ndarray                      # (k,) ill-conditioned samples
    reachable: np.ndarray                   # (k,)
    samples: np.ndarray                     # (k,)
    details: tuple[DesignCount, ...] = field(default=(), repr=False)

    def index(self, design: ArrayLike) -> int:
        """Row of ``design`` (m), matched to 0.1 mm.

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m.

        Returns
        -------
        int
            Row in ``designs``; a ValueError when not exactly one row matches.
        """
        hits = np.flatnonzero(np.all(np.abs(self.designs - np.asarray(design, float)) < 1e-4, axis=1))
        if hits.size != 1:
            raise ValueError(f"design {tuple(design)!r} is not in this sweep")
        return int(hits[0])

    def count(self, design: ArrayLike) -> int:
        """Ill-conditioned samples of ``design``.

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m (matched as in ``index``).

        Returns
        -------
        int
        """
        return int(self.counts[self.index(design)])

    def winners(self) -> list[tuple[float, float, float]]:
        """Every design attaining the minimum count (the best configurations).

        Returns
        -------
        list of tuple of float
            Designs ``(a1, a2, a3)`` in m, in table order.
        """
        best = self.counts.min()
        return [tuple(float(v) for v in self.designs[i]) for i in np.flatnonzero(self.counts == best)]

    def ranks(self) -> np.ndarray:
        """Competition rank of each design (1 = fewest ill-conditioned samples; ties share).

        Returns
        -------
        ndarray of int, shape (k,)

        Examples
        --------
        >>> designs = np.array([[0.10, 0.10, 0.05], [0.12, 0.10, 0.05], [0.10, 0.12, 0.05]])
        >>> r = SweepResult(SAMPLINGS["grid"], "+-", designs, np.array([7, 3, 7]), np.full(3, 9), np.full(3, 10))
        >>> r.ranks().tolist(), r.winners(), r.top(2)
        ([2, 1, 2], [(0.12, 0.1, 0.05)], [((0.12, 0.1, 0.05), 3), ((0.1, 0.1, 0.05), 7)])
        """
        return 1 + np.searchsorted(np.sort(self.counts), self.counts, side="left")

    def rank(self, design: ArrayLike) -> int:
        """Competition rank of ``design`` (``ranks``).

        Parameters
        ----------
        design : array_like, shape (3,)
            Link lengths ``(a1, a2, a3)``, m (matched as in ``index``).

        Returns
        -------
        int
        """
        return int(self.ranks()[self.index(design)])

    def top(self, k: int = 5) -> list[tuple[tuple[float, float, float], int]]:
        """The ``k`` designs with the fewest ill-conditioned samples (stable in table order).

        Parameters
        ----------
        k : int
            How many.

        Returns
        -------
        list of (tuple of float, int)
            ``(design, count)`` pairs, designs in m.
        """
        order = np.argsort(self.counts, kind="stable")[:k]
        return [(tuple(float(v) for v in self.designs[i]), int(self.counts[i])) for i in order]


def link_length_sweep(sampling: Sampling | str, designs: ArrayLike, *, working_mode: str = "+-",
                      threshold: float = ILL_CONDITIONED) -> SweepResult:
    """``count_ill_conditioned`` for every design of a five-bar link-length sweep.

    Parameters
    ----------
    sampling : Sampling or str
        How each design's workspace is sampled, or the name of one of ``SAMPLINGS``.
    designs : array_like, shape (k, 3)
        Link lengths ``(a1, a2, a3)`` in metres, one design per row (``link_length_designs``).
    working_mode : str
        The five-bar's working mode, ``"+-"`` (both elbows out) by default.
    threshold : float
        A sample counts when its condition number exceeds this.

    Returns
    -------
    SweepResult
        The counts, reachable and total samples of each design, in the order of ``designs``.
    """
    if isinstance(sampling, str):
        if sampling not in SAMPLINGS:
            raise ValueError(f"sampling must be one of {', '.join(map(repr, SAMPLINGS))} or a Sampling, "
                             f"got {sampling!r}")
        sampling = SAMPLINGS[sampling]
    d = np.asarray(designs, float).reshape(-1, 3)
    details = tuple(count_ill_conditioned(row, sampling, working_mode=working_mode, threshold=threshold)
                    for row in d)
    return SweepResult(sampling, working_mode, d,
                       np.array([c.ill for c in details]), np.array([c.reachable for c in details]),
                       np.array([c.samples for c in details]), details)


def kendall_tau(a: SweepResult, b: SweepResult) -> float:
    """Kendall's tau-b between two sweeps' counts over the same designs (ties handled).

    Parameters
    ----------
    a, b : SweepResult
        Sweeps over the same designs in the same order.

    Returns
    -------
    float
        In [-1, 1]; 1 when both rank the designs alike.
    """
    if a.designs.shape != b.designs.shape or not np.allclose(a.designs, b.designs):
        raise ValueError("kendall_tau needs two sweeps over the same designs in the same order")
    from scipy.stats import kendalltau

    return float(kendalltau(a.counts, b.counts).statistic)
