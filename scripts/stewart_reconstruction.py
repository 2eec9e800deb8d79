"""Paper 001 Table IV: a Stewart platform that reaches W at +-30 deg, or why none can (issue 23 sec. 2).

Usage, from the repository root::

    python scripts/stewart_reconstruction.py            # the search and its findings (~2 min)
    python scripts/stewart_reconstruction.py --sweep    # also one parameter at a time around the optimum (~7 min)

Table IV's GII, 0.096, is a minimum over all of W (Table II: +-8 x +-5 x +-5 cm about a point 25 cm
from the base, +-30 deg), so the paper's Stewart platform reaches every pose of W. Our shipped preset
(``stewart_platform``: legs 9-18 cm, a 10 cm tool offset) reaches almost nothing of it. This script
asks which geometry could, in four steps.

1. **The stroke.** A leg's length is ``|o + R p_i - b_i|``. At one orientation ``R`` the point
   ``o + R p_i`` sweeps a copy of W's position box (16 x 10 x 10 cm), and that box holds a ball of
   radius 5 cm. The distances from any point ``b_i`` to a ball of radius 5 cm span at least 10 cm,
   so every leg needs a stroke of at least 10 cm, whatever the geometry. The paper's legs give
   9 <= q <= 18 cm, a 9 cm stroke. ``stroke_needed`` checks this on Table II's own 2,057 positions:
   it searches the anchor points ``c = b_i - R p_i`` for the smallest spread of distances.
2. **Readings of Table IV's parameters** (``READINGS``; Fig. 10 is not in our text):

   * ``model``: ``kinematics/stewart.py``'s own reading: l1 the tool offset (task point above the
     platform's joint plane), l4 the base radius, l6 the platform radius, the three-fold 6-6 layout
     with pair half-angles of 15 deg; l5, l7, eta1 and eta2 are unused.
   * ``pairs``: the reading ``kinematics/inoue.py`` gives the same symbols on the Inoue platform, with
     each five-bar replaced by two legs: pair k's two base joints l1 apart on the tangent through its
     centre, pair 1's centre at radius l4 on azimuth 90 deg, pairs 2 and 3 at radius l5 on 90 +- eta1;
     pair k's two legs meet at platform point k, point 1 at radius l6 on 90 deg, points 2 and 3 at
     radius l7 on 90 +- eta2, in the platform plane, whose origin is the task point (a 6-3 platform).
     Legs q1, q2 are pair 1; q3, q4 pair 2; q5, q6 pair 3: the mirror x -> -x swaps q3 and q6, q4 and
     q5, eq. 18's pairs (Q1 on q3 and q6, Q2 on q4 and q5).
   * ``pairs_lever``: ``pairs`` with each base joint l1 from its pair's centre (2 l1 apart), the
     analogue of the adopted Twin-Pantograph reading (``ujoint_lever = 1.0``: l6 a lever from the
     centre, not a separation).

   For each, Table IV's printed optimum on Table II's 4,492,488 poses: its leg lengths, its joint
   bends, whether it reaches W with legs of 9-18 cm, or with legs of any length and bends <= 85 deg
   (the paper states a stroke only for the semi-dextrous comparison of Figs. 13-14, not for Table IV,
   and no joint limit for its Stewart platform), and its GII with legs of any length and bends not
   limited.
3. **The model's reading over Table IV's grid**: all 7 x 7 x 7 (l1, l4, l6) on the studies' coarse W
   with legs 9-18 cm and with legs of any length (joint bends <= 85 deg, the model's default).
4. With ``--sweep``: under the ``pairs`` readings, each of l1, l4, l5, l6, l7, eta1, eta2 over its
   Table IV range with the others at the optimum (coarse W, Q1 and Q2 over Table IV's 49 pairs).

What can be a preset: only what ``kinematics.StewartPlatform`` expresses, one base radius, one
platform radius and a three-fold 6-6 layout (pair half-angles below 60 deg). ``representable``
says why a reading's design is or is not one.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from kinematics import StewartPlatform  # noqa: E402
from scripts import three_platforms as T  # noqa: E402

DEG = math.pi / 180
#: Table IV's design space, cm and deg: (min, max, step); the optimum is ``three_platforms.TABLE4``.
TABLE4_SPACE = {"l1": (4.0, 16.0, 2.0), "l4": (2.0, 14.0, 2.0), "l5": (2.0, 14.0, 2.0), "l6": (1.0, 7.0, 1.0),
                "l7": (1.0, 7.0, 1.0), "eta1": (110.0, 140.0, 5.0), "eta2": (140.0, 175.0, 5.0),
                "Q1": (0.3, 1.5, 0.2), "Q2": (0.3, 1.5, 0.2)}
#: The paper's legs (sec. V, for Figs. 13-14), m.
PAPER_LEGS = (0.09, 0.18)
#: "Any length": legs from 1 mm to 10 m.
FREE_LEGS = (0.001, 10.0)
#: The model's default joint bend limit (rad), at both ends of a leg: what "reaches" is checked
#: against. The GIIs are computed without a bend limit (``NO_LIMIT``): the paper gives its Stewart
#: platform none (the 85 deg of sec. V is the U-joints' of the other two).
JOINT_LIMIT = 85 * DEG
NO_LIMIT = math.pi
#: The model reading's pair half-angles (the model's defaults; not Table IV parameters).
HALF_ANGLE = 15 * DEG


@dataclass(frozen=True)
class Reading:
    key: str
    label: str


READINGS = (
    Reading("model", "model's reading: l1 tool offset, l4 / l6 radii"),
    Reading("pairs", "pairs reading: l1 the pair's joint separation"),
    Reading("pairs_lever", "pairs reading: l1 each joint's distance from the pair's centre"),
)
BY_KEY = {r.key: r for r in READINGS}


def values(name: str) -> np.ndarray:
    """Table IV's grid of one parameter (cm, deg or a ratio)."""
    lo, hi, step = TABLE4_SPACE[name]
    return np.round(np.arange(lo, hi + step / 2, step), 6)


class PairsStewart(StewartPlatform):
    """A Stewart platform whose joints are given, not made from the three-fold layout.

    ``base`` and ``top`` (6, 3), m: the base joints in the base frame and the platform joints in the
    platform frame (origin at the task point). Everything else (IK, force map, leg and bend limits,
    leg forces) is ``kinematics.StewartPlatform``'s, from ``params``. ``replace`` would drop the
    joints: build a new one instead.
    """

    def __init__(self, base: np.ndarray, top: np.ndarray, **params) -> None:
        super().__init__(**params)
        object.__setattr__(self, "_base", np.asarray(base, float).copy())
        object.__setattr__(self, "_top", np.asarray(top, float).copy())

    def base_joints(self) -> np.ndarray:
        return self._base.copy()

    def platform_joints(self) -> np.ndarray:
        return self._top.copy()

    def __eq__(self, other: object) -> bool:
        return (type(other) is type(self) and other.params == self.params and np.array_equal(other._base, self._base)
                and np.array_equal(other._top, self._top))

    def __hash__(self) -> int:
        return hash((type(self), self.params, self._base.tobytes(), self._top.tobytes()))


def pairs_joints(d: dict, lever: float) -> tuple[np.ndarray, np.ndarray]:
    """Base and platform joints (6, 3), m, of the ``pairs`` readings; each base joint ``lever * l1`` from
    its pair's centre (0.5: ``pairs``, 1.0: ``pairs_lever``)."""
    phi_b = np.array([90.0, 90.0 + d["eta1"], 90.0 - d["eta1"]]) * DEG
    phi_p = np.array([90.0, 90.0 + d["eta2"], 90.0 - d["eta2"]]) * DEG
    rb = np.array([d["l4"], d["l5"], d["l5"]]) / 100
    rp = np.array([d["l6"], d["l7"], d["l7"]]) / 100
    half = lever * d["l1"] / 100
    base, top = [], []
    for k in range(3):
        centre = rb[k] * np.array([math.cos(phi_b[k]), math.sin(phi_b[k]), 0.0])
        tangent = np.array([-math.sin(phi_b[k]), math.cos(phi_b[k]), 0.0])
        point = rp[k] * np.array([math.cos(phi_p[k]), math.sin(phi_p[k]), 0.0])
        for s in (-1.0, 1.0):
            base.append(centre + s * half * tangent)
            top.append(point)
    return np.array(base), np.array(top)


def stewart(reading: Reading, design: dict, *, legs=FREE_LEGS, joint_limit: float = NO_LIMIT) -> StewartPlatform:
    """Table IV's ``design`` (cm, deg, Q1, Q2) under ``reading``, legs in ``legs`` (m), joint bends up to
    ``joint_limit`` (rad; default: not limited)."""
    forces = (T.LEG_FORCE, T.LEG_FORCE, design["Q1"] * T.LEG_FORCE, design["Q2"] * T.LEG_FORCE,
              design["Q2"] * T.LEG_FORCE, design["Q1"] * T.LEG_FORCE)
    common = {"min_leg": legs[0], "max_leg": legs[1], "base_joint_limit": joint_limit,
              "platform_joint_limit": joint_limit, "motor_forces": forces}
    if reading.key == "model":
        return StewartPlatform(base_radius=design["l4"] / 100, platform_radius=design["l6"] / 100,
                               tool_offset=design["l1"] / 100, base_half_angle=HALF_ANGLE,
                               platform_half_angle=HALF_ANGLE, **common)
    base, top = pairs_joints(design, 0.5 if reading.key == "pairs" else 1.0)
    return PairsStewart(base, top, **common)


def representable(reading: Reading, design: dict) -> str:
    """Why ``design`` under ``reading`` is or is not a ``kinematics.StewartPlatform`` (a preset)."""
    if reading.key == "model":
        return "yes: it is the model's own reading (l5, l7, eta1, eta2 unused)"
    why = []
    if design["l4"] != design["l5"] or design["eta1"] != 120.0:
        why.append("two base radii or eta1 != 120 deg (the model's pairs are three-fold)")
    if design["l6"] != design["l7"] or design["eta2"] != 120.0:
        why.append(f"platform points at radii {design['l6']:g} / {design['l7']:g} cm and 90 +- {design['eta2']:g} deg "
                   "(the model's platform joints are three-fold on one circle)")
    why.append("two legs meeting at one platform point (the model's platform pair half-angle must be below 60 deg)")
    return "no: " + "; ".join(why)


# -- 1. the stroke ---------------------------------------------------------------------------------
def distance_range(anchors: np.ndarray, points: np.ndarray, chunk: int = 2048) -> tuple[np.ndarray, np.ndarray]:
    """Shortest and longest distance from each anchor (A, 3) to ``points`` (P, 3), each (A,), m."""
    lo, hi = np.empty(len(anchors)), np.empty(len(anchors))
    for s in range(0, len(anchors), chunk):
        d = np.linalg.norm(anchors[s:s + chunk, None, :] - points[None], axis=-1)
        lo[s:s + chunk], hi[s:s + chunk] = d.min(1), d.max(1)
    return lo, hi


def spread(anchors: np.ndarray, points: np.ndarray) -> np.ndarray:
    """max - min of the distances from each anchor (A, 3) to ``points`` (P, 3), (A,), m."""
    lo, hi = distance_range(anchors, points)
    return hi - lo


def fibonacci_sphere(n: int) -> np.ndarray:
    """n nearly even unit vectors (n, 3), with the six axis directions added."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = math.pi * (1 + 5 ** 0.5) * i
    v = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], -1)
    return np.concatenate([v, np.eye(3), -np.eye(3)])


@dataclass(frozen=True)
class Stroke:
    needed: float           # the smallest spread found, m
    anchor: np.ndarray      # where, relative to W's centre, m
    anchors: int            # anchors searched
    within_paper_legs: int  # anchors with every distance in [9, 18] cm


def stroke_needed(points: np.ndarray | None = None, *, directions: int = 2000, distances: int = 60) -> Stroke:
    """Search anchor points ``c`` for the smallest spread (max - min) of their distances to W's positions.

    Anchors: ``directions`` directions from W's centre times ``distances`` distances from 1 mm to
    100 m (log-spaced), then a Nelder-Mead refinement from the best ten. A leg's stroke must cover
    the spread of its own anchor ``b_i - R p_i`` at each orientation, so the smallest spread is a
    lower bound on the stroke of every leg of every geometry (at a single orientation; more
    orientations only add poses).
    """
    from scipy.optimize import minimize

    pts = T.positions(step=T.TABLE2_STEP) if points is None else points
    centre = pts.mean(0)
    dirs = fibonacci_sphere(directions)
    radii = np.geomspace(1e-3, 100.0, distances)
    anchors = centre + (dirs[:, None, :] * radii[None, :, None]).reshape(-1, 3)
    lo, hi = distance_range(anchors, pts)
    s = hi - lo
    inside = int(np.count_nonzero((lo >= PAPER_LEGS[0]) & (hi <= PAPER_LEGS[1])))
    best = np.argsort(s)[:10]
    found, where = float(s[best[0]]), anchors[best[0]]
    for b in best:
        res = minimize(lambda c: float(spread(c[None], pts)[0]), anchors[b], method="Nelder-Mead",
                       options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 2000})
        if res.fun < found:
            found, where = float(res.fun), res.x
    return Stroke(found, where - centre, len(anchors), inside)


# -- 2. the printed optimum under each reading ------------------------------------------------------
@dataclass(frozen=True)
class Printed:
    reading: Reading
    legs: tuple[float, float]          # shortest and longest leg over W, m
    bends: tuple[float, float]         # largest base and platform joint bends over W, rad
    reaches_paper_legs: bool           # every pose with legs 9-18 cm and bends <= 85 deg
    reaches_free_legs: bool            # every pose with bends <= 85 deg
    poses: int
    gii: float                         # legs of any length, bends not limited
    representable: str


def printed(reading: Reading, ws: T.Workspace | None = None, *, chunk: int = T.CHUNK) -> Printed:
    """Table IV's optimum under ``reading`` over ``ws`` (default: Table II's 4,492,488 poses)."""
    ws = T.table2() if ws is None else ws
    mech = stewart(reading, T.TABLE4)
    lo, hi, bmax, tmax = math.inf, 0.0, 0.0, 0.0
    for s in range(0, ws.size, chunk):
        x = ws.poses(s, s + chunk)
        q, _ = mech.inverse(x)
        b = mech.bend_angles(x)
        lo, hi = min(lo, float(q.min())), max(hi, float(q.max()))
        bmax, tmax = max(bmax, float(b[..., 0].max())), max(tmax, float(b[..., 1].max()))
    bends_ok = bmax <= JOINT_LIMIT and tmax <= JOINT_LIMIT
    paper_ok = bends_ok and lo >= PAPER_LEGS[0] and hi <= PAPER_LEGS[1]
    g = T.gii(mech, ws).gii
    return Printed(reading, (lo, hi), (bmax, tmax), paper_ok, bends_ok, ws.size, g, representable(reading, T.TABLE4))


# -- 3. the model's reading over Table IV's grid ----------------------------------------------------
@dataclass(frozen=True)
class GridScan:
    designs: int
    reach_paper_legs: int
    reach_free_legs: int
    best_gii: float
    best: dict
    best_legs: tuple[float, float]


def scan_model_reading(ws: T.Workspace | None = None) -> GridScan:
    """All (l1, l4, l6) of Table IV under the model's reading, Q1 and Q2 at the optimum's, on ``ws``
    (default: the studies' coarse W). Reach with legs 9-18 cm and with legs of any length (bends <=
    85 deg); the best GII among the second (``resources/studies/stewart_table4.toml`` also varies Q1, Q2)."""
    ws = T.coarse() if ws is None else ws
    x = ws.poses()
    reading = BY_KEY["model"]
    n = paper = free = 0
    best, best_d, best_legs = -math.inf, {}, (math.nan, math.nan)
    for l1 in values("l1"):
        for l4 in values("l4"):
            for l6 in values("l6"):
                d = dict(T.TABLE4, l1=float(l1), l4=float(l4), l6=float(l6))
                mech = stewart(reading, d, joint_limit=JOINT_LIMIT)
                q, ok = mech.inverse(x)
                feas = ok & mech.feasible(q, x)
                n += 1
                if not feas.all():
                    continue
                free += 1
                paper += bool(q.min() >= PAPER_LEGS[0] and q.max() <= PAPER_LEGS[1])
                g = T.gii(mech, ws).gii
                if g > best:
                    best, best_d, best_legs = g, d, (float(q.min()), float(q.max()))
    return GridScan(n, paper, free, best, best_d, best_legs)


# -- 4. one parameter at a time ---------------------------------------------------------------------
def sweep(reading: Reading, ws: T.Workspace | None = None) -> dict[str, list[tuple[float, float]]]:
    """Each geometric parameter over its Table IV range, the others at the optimum; the GII (legs of any
    length, bends not limited) at the best of Table IV's 49 (Q1, Q2) pairs, on ``ws`` (default: the coarse W)."""
    ws = T.coarse() if ws is None else ws
    qs = [(a, b) for a in values("Q1") for b in values("Q2")]
    out = {}
    for name in ("l1", "l4", "l5", "l6", "l7", "eta1", "eta2"):
        row = []
        for v in values(name):
            d = dict(T.TABLE4, **{name: float(v)})
            row.append((float(v), max(T.gii(stewart(reading, dict(d, Q1=a, Q2=b)), ws).gii for a, b in qs)))
        out[name] = row
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sweep", action="store_true", help="also sweep each parameter around the optimum")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    pts = T.positions(step=T.TABLE2_STEP)
    st = stroke_needed(pts)
    print("1. The stroke W needs (any geometry)")
    print(f"   W's positions (Table II): {len(pts):,}; anchor points searched: {st.anchors:,} + Nelder-Mead from "
          f"the best 10")
    far = float(np.linalg.norm(st.anchor))
    print(f"   smallest spread of distances found: {st.needed * 100:.3f} cm, at an anchor {far:.3g} m from W's centre "
          f"along {np.round(st.anchor / far, 3).tolist()} (W's 10 cm width, approached from far away); "
          f"continuous bound: 10 cm (the ball inscribed in the 16 x 10 x 10 cm box)")
    print(f"   anchors with every position within 9-18 cm: {st.within_paper_legs}; the paper's legs give "
          f"{(PAPER_LEGS[1] - PAPER_LEGS[0]) * 100:g} cm")
    print("   => no Stewart platform, of any geometry, reaches W's positions with 9 <= q <= 18 cm")
    print()
    print("2. Table IV's optimum (l1 10, l4 6, l5 6, l6 3, l7 4 cm, eta1 120, eta2 170 deg, Q1 0.5, Q2 0.9) "
          "on Table II's 4,492,488 poses")
    for r in READINGS:
        p = printed(r)
        print(f"   {r.key} ({r.label}):")
        print(f"     legs {p.legs[0] * 100:.2f} to {p.legs[1] * 100:.2f} cm (stroke {(p.legs[1] - p.legs[0]) * 100:.2f}"
              f" cm); largest bends: base {math.degrees(p.bends[0]):.1f}, platform {math.degrees(p.bends[1]):.1f} deg")
        print(f"     reaches W with legs 9-18 cm: {'yes' if p.reaches_paper_legs else 'no'}; with legs of any "
              f"length (bends <= 85 deg): {'yes' if p.reaches_free_legs else 'no'}; GII (legs of any length, bends not "
              f"limited) {T._fmt(p.gii, 4)} (paper 0.096)")
        print(f"     a kinematics.StewartPlatform preset? {p.representable}")
    print()
    scan = scan_model_reading()
    print("3. The model's reading over Table IV's 7 x 7 x 7 (l1, l4, l6), coarse W (1,539 poses), Q1 0.5, Q2 0.9")
    print(f"   designs: {scan.designs}; reach W with legs 9-18 cm: {scan.reach_paper_legs}; with legs of any length "
          f"(bends <= 85 deg): {scan.reach_free_legs}")
    if scan.best:
        print(f"   best GII among them: {T._fmt(scan.best_gii, 4)} at l1 {scan.best['l1']:g}, l4 {scan.best['l4']:g}, "
              f"l6 {scan.best['l6']:g} cm (legs {scan.best_legs[0] * 100:.1f} to {scan.best_legs[1] * 100:.1f} cm); "
              f"paper 0.096")
    if args.sweep:
        print()
        print("4. One parameter at a time around the optimum (coarse W, best of Table IV's 49 Q1, Q2 pairs)")
        for key in ("pairs", "pairs_lever"):
            print(f"   {key}:")
            for name, row in sweep(BY_KEY[key]).items():
                cells = ", ".join(f"{v:g}: {T._fmt(g, 3)}" for v, g in row)
                print(f"     {name}: {cells}")
    print(f"\n({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
