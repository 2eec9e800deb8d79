"""Paper 001 Tables III-V: the force GII of the three 6-DOF platforms (issue 23 sec. 2).

Usage, from the repository root::

    python scripts/three_platforms.py               # the printed designs on the studies' workspace (~10 s)
    python scripts/three_platforms.py --table2      # also on Table II's 4,492,488 samples (~5 min)
    python scripts/three_platforms.py --studies     # also run the three reduced studies (~15 min on 2 cores)

Paper 001 optimizes the Twin-Pantograph (Table III, 6-DOF: roll q7 actuated, waist q4 passive),
the Stewart platform (Table IV) and the Inoue platform (Table V) by the force GII (eq. 11) with
Table I's task scaling (S_T, eq. 19) in the end-effector frame, over the workspace W of Table II
(+-8 x +-5 x +-5 cm, 25 cm from the base, +-30 deg). It prints 0.327, 0.096 and 0.215 and says
the Twin-Pantograph's is "3.4 and 1.5 times larger".

What this script does, with nothing re-optimized:

* The paper's printed designs (``TABLE3``, ``TABLE4``, ``TABLE5``) evaluated on the studies' coarse
  W (``resources/studies/twin_pantograph_table3.toml``, ``stewart_table4.toml``, ``inoue_table5.toml``:
  3 x 3 x 3 positions at 80 / 50 / 50 mm steps, 19 tip directions within 30 deg (eq. 16, N = 2) x
  rolls -30, 0, 30 deg: 1,539 poses) and, with ``--table2``, on Table II's own sampling (17 x 11 x
  11 positions at 1 cm, 168 tip directions (eq. 16, N = 7, the paper's floor) x 13 rolls every
  5 deg: 4,492,488 poses). The full W is used for all three (the paper halves it for the parallel
  platforms by their symmetry; both our models are symmetric about the jk plane, so it changes
  nothing but the cost).
* The Twin-Pantograph under the adopted reading of issue 23 sec. 1 (``ujoint_lever = 1.0``: each
  U-joint l6 from the pen's centre) first, then under the model's default (0.5).
* The Stewart platform under the readings of ``scripts/stewart_reconstruction.py``: the model's own
  (``kinematics/stewart.py``), and the two "pairs" readings that model cannot express.
* ``--studies`` runs the three reduced studies (coarse subgrids of Tables III-V that hold the
  printed optima) and prints their optima.

``gii`` computes a GII exactly as ``metrics.design.evaluators.Generic`` does (IK, limits, force
map, rows in the end-effector frame, scaled singular values), in chunks so that Table II's 4.5
million poses fit; ``tests/test_three_platforms.py`` checks it against the studies' evaluation
and pins the coarse figures.
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

from kinematics import InouePlatform, TwinPantograph  # noqa: E402
from kinematics.rotations import rotation_matrix, rotation_vector  # noqa: E402
from metrics import gii as gii_mod  # noqa: E402
from metrics.orientations import orientation_samples  # noqa: E402

#: The paper's optimum GIIs (Tables III, IV, V) and its ratios ("3.4 and 1.5 times larger").
PAPER = {"twin": 0.327, "stewart": 0.096, "inoue": 0.215}
PAPER_RATIOS = {"stewart": 3.4, "inoue": 1.5}
#: The printed optima, cm and deg; Q1, Q2 as the paper's actuator scale factors (eqs. 17, 18).
TABLE3 = {"l1": 3.0, "l2": 16.0, "l3": 22.0, "l4": 2.0, "l6": 3.0, "Q1": 1.9, "Q2": 0.03}
TABLE4 = {"l1": 10.0, "l4": 6.0, "l5": 6.0, "l6": 3.0, "l7": 4.0, "eta1": 120.0, "eta2": 170.0, "Q1": 0.5, "Q2": 0.9}
TABLE5 = {"l1": 2.0, "l2": 16.0, "l3": 24.0, "l4": 2.0, "l5": 2.0, "l6": 2.0, "l7": 4.0, "eta1": 120.0,
          "eta2": 170.0, "Q1": 0.75, "Q2": 0.75}
#: The Twin-Pantograph's readings (issue 23 sec. 1), the adopted one first: key, label, ujoint_lever.
TWIN_READINGS = (("mid_2l6", "adopted, ujoint_lever = 1.0", 1.0), ("mid", "default, ujoint_lever = 0.5", 0.5))
#: The actuators' base torque (N m) and force (N) that Q1 and Q2 scale (only the ratios enter the GII).
SHOULDER_TORQUE = 0.1
LEG_FORCE = 10.0
#: Table II: W's centre along k, half-widths (m), the bound (rad) and its sampling.
CENTRE_Z = 0.25
HALF = (0.08, 0.05, 0.05)
BOUND = math.radians(30.0)
TABLE2_STEP = 0.01
TABLE2_RINGS = 7                       # eq. 16 with the paper's floor: 168 tip directions
TABLE2_ROLLS = np.radians(np.arange(-30.0, 30.1, 5.0))          # 13
#: The studies' coarse W.
COARSE_RESOLUTION = (3, 3, 3)
COARSE_RINGS = 2
COARSE_ROLLS = np.radians([-30.0, 0.0, 30.0])
#: Poses per chunk of ``gii`` (a 6 x 6 force map and its SVD per pose: ~1 kB each).
CHUNK = 1 << 16
STUDIES = {"twin": "twin_pantograph_table3", "stewart": "stewart_table4", "inoue": "inoue_table5"}


def positions(resolution=None, step=None) -> np.ndarray:
    """W's positions (P, 3), m: a grid of ``resolution`` points per axis, or at ``step`` (Table II)."""
    if step is not None:
        axes = [np.linspace(-h, h, int(round(2 * h / step)) + 1) for h in HALF]
    else:
        axes = [np.linspace(-h, h, n) for h, n in zip(HALF, resolution)]
    axes[2] = axes[2] + CENTRE_Z
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)


def orientations(rings: int, rolls, rule: str = "exact") -> np.ndarray:
    """Rotation vectors (K, 3) of the tip directions (pen axis y) times the rolls, as the studies make them."""
    s = orientation_samples(BOUND, rings, roll=np.asarray(rolls, float), rule=rule, tool_axis=(0.0, 1.0, 0.0))
    return rotation_vector(s.rotations)


@dataclass(frozen=True)
class Workspace:
    """A sampled W: positions (P, 3) times orientations (K, 3)."""

    name: str
    positions: np.ndarray
    orientations: np.ndarray

    @property
    def size(self) -> int:
        return len(self.positions) * len(self.orientations)

    def poses(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Poses ``start:stop`` (position-major), (n, 6)."""
        stop = self.size if stop is None else min(stop, self.size)
        idx = np.arange(start, stop)
        k = len(self.orientations)
        return np.concatenate([self.positions[idx // k], self.orientations[idx % k]], -1)


def coarse() -> Workspace:
    """The studies' W: 27 positions x 57 orientations = 1,539 poses."""
    return Workspace("coarse (studies)", positions(COARSE_RESOLUTION), orientations(COARSE_RINGS, COARSE_ROLLS))


def table2() -> Workspace:
    """Table II's W: 2,057 positions x 2,184 orientations = 4,492,488 poses."""
    return Workspace("Table II", positions(step=TABLE2_STEP), orientations(TABLE2_RINGS, TABLE2_ROLLS, "float"))


@dataclass(frozen=True)
class Evaluation:
    """A design's GII over a sampled W, with where it fails and its leg or joint extremes."""

    gii: float                  # nan when a pose is out of reach or beyond a limit
    reached: int                # poses reachable and within every limit
    poses: int
    sigma_min: float
    sigma_max: float
    seconds: float

    @property
    def reaches(self) -> bool:
        return self.reached == self.poses


def gii(mech, ws: Workspace, *, chunk: int = CHUNK) -> Evaluation:
    """Eq. 11 over ``ws`` as ``metrics.design.evaluators.Generic`` computes it: every pose must be
    reachable and feasible (``infeasible = "fail"``), the force map's rows in the end-effector frame,
    S_J from ``torque_limits``, S_T of Table I (eq. 19)."""
    t0 = time.perf_counter()
    lo, hi, reached = math.inf, 0.0, 0
    s_t = gii_mod.HUMAN_HAND_S_T
    limits = mech.torque_limits()
    for start in range(0, ws.size, chunk):
        x = ws.poses(start, start + chunk)
        q, ok = mech.inverse(x)
        feas = ok.copy()
        if ok.any():
            feas[ok] = mech.feasible(q[ok], x[ok])
        reached += int(feas.sum())
        if not feas.any():
            continue
        xf, qf = x[feas], q[feas]
        mat = gii_mod.rotate_task_rows(mech.force_map(qf, xf), rotation_matrix(xf[:, 3:6]))
        sv = gii_mod.scaled_singular_values(mat, limits, s_t, kind="force_map")
        lo, hi = min(lo, float(sv[:, -1].min())), max(hi, float(sv[:, 0].max()))
    value = lo / hi if reached == ws.size and hi > 0 else math.nan
    return Evaluation(value, reached, ws.size, lo, hi, time.perf_counter() - t0)


def twin(lever: float, design: dict = TABLE3) -> TwinPantograph:
    """Table III's 6-DOF Twin-Pantograph (roll q7 actuated, waist q4 passive) under ``ujoint_lever``."""
    d = design
    torques = (d["Q1"] * SHOULDER_TORQUE,) + (SHOULDER_TORQUE,) * 5 + (d["Q2"] * SHOULDER_TORQUE,)
    return TwinPantograph(shoulder_separation=d["l1"] / 100, upper_arm=d["l2"] / 100, forearm=d["l3"] / 100,
                          unit_separation=d["l4"] / 100, pen_length=d["l6"] / 100, ujoint_lever=lever,
                          redundant_waist="passive", roll_actuator="active", motor_torques=torques)


def inoue(design: dict = TABLE5) -> InouePlatform:
    """Table V's Inoue platform (kinematics/inoue.py's reading; eq. 18: q3 = q6 = Q1 q1, q4 = q5 = Q2 q1)."""
    d, deg = design, math.pi / 180
    t = SHOULDER_TORQUE
    torques = (t, t, d["Q1"] * t, d["Q2"] * t, d["Q2"] * t, d["Q1"] * t, t, t, t)
    return InouePlatform(shoulder_separation=d["l1"] / 100, upper_arm=d["l2"] / 100, forearm=d["l3"] / 100,
                         base_apex_radius=d["l4"] / 100, base_pair_radius=d["l5"] / 100,
                         platform_apex_radius=d["l6"] / 100, platform_pair_radius=d["l7"] / 100,
                         base_pair_angle=d["eta1"] * deg, platform_pair_angle=d["eta2"] * deg, motor_torques=torques)


@dataclass(frozen=True)
class Row:
    platform: str           # twin | stewart | inoue
    reading: str
    label: str
    paper: float
    coarse: Evaluation
    table2: Evaluation | None = None


def rows(with_table2: bool = False) -> list[Row]:
    """The printed designs under every reading, on the coarse W (and Table II's with ``with_table2``)."""
    from scripts import stewart_reconstruction as S

    cases = [("twin", key, f"Twin-Pantograph, Table III ({label})", twin(lever)) for key, label, lever in TWIN_READINGS]
    cases += [("stewart", r.key, f"Stewart platform, Table IV ({r.label})", S.stewart(r, TABLE4))
              for r in S.READINGS]
    cases.append(("inoue", "model", "Inoue platform, Table V (kinematics/inoue.py)", inoue()))
    ws_c = coarse()
    ws_2 = table2() if with_table2 else None
    out = []
    for platform, key, label, mech in cases:
        out.append(Row(platform, key, label, PAPER[platform], gii(mech, ws_c),
                       gii(mech, ws_2) if ws_2 is not None else None))
    return out


def ratios(table: list[Row], which: str = "coarse") -> list[tuple[str, str, str, float, float]]:
    """(Twin reading, other platform, its reading, ours, paper) for the ratios Twin / Stewart and Twin / Inoue."""
    out = []
    for t in (r for r in table if r.platform == "twin"):
        for o in (r for r in table if r.platform != "twin"):
            a, b = getattr(t, which), getattr(o, which)
            value = a.gii / b.gii if a is not None and b is not None and b.gii > 0 else math.nan
            out.append((t.reading, o.platform, o.reading, value, PAPER_RATIOS[o.platform]))
    return out


def _fmt(v: float, digits: int = 3) -> str:
    if v is None or not math.isfinite(v):
        return "no reach"
    return f"{v:.{digits}g}" if abs(v) >= 1e-3 else f"{v:.2e}"


def _ratio(value: float) -> str:
    """A ratio of GIIs; one over a GII of nearly 0 (a design singular in W) is not a comparison."""
    return "n/a (singular in W)" if math.isfinite(value) and value > 1e3 else _fmt(value, 3)


def markdown(table: list[Row]) -> str:
    """The results table and the ratios, as in docs/three_platforms.md."""
    t2 = any(r.table2 is not None for r in table)
    head = "| platform and reading | paper | coarse W (1,539 poses) | ratio |"
    sep = "| --- | ---: | ---: | ---: |"
    if t2:
        head += " Table II (4,492,488 poses) | ratio |"
        sep += " ---: | ---: |"
    lines = [head, sep]
    for r in table:
        line = f"| {r.label} | {r.paper:g} | {_fmt(r.coarse.gii, 4)} | {_fmt(r.coarse.gii / r.paper, 3)} |"
        if t2:
            g = r.table2.gii if r.table2 is not None else math.nan
            line += f" {_fmt(g, 4)} | {_fmt(g / r.paper, 3)} |"
        lines.append(line)
    lines += ["", "| Twin reading | over | reading | ours (coarse) | paper |", "| --- | --- | --- | ---: | ---: |"]
    for tr, other, orr, value, paper in ratios(table):
        lines.append(f"| `{tr}` | {other} | `{orr}` | {_ratio(value)} | {paper:g} |")
    if t2:
        lines += ["", "| Twin reading | over | reading | ours (Table II) | paper |",
                  "| --- | --- | --- | ---: | ---: |"]
        for tr, other, orr, value, paper in ratios(table, "table2"):
            lines.append(f"| `{tr}` | {other} | `{orr}` | {_ratio(value)} | {paper:g} |")
    return "\n".join(lines)


def run_studies(workers: int | None = None) -> list[tuple[str, object, object]]:
    """Run the three reduced studies: (key, run study, result) per run (the Twin's has one per reading)."""
    from metrics.design import build_study, run_study
    from resources import load_study

    out = []
    for platform in ("twin", "stewart", "inoue"):
        st = build_study(load_study(STUDIES[platform]))
        for run in st.runs():
            out.append((platform, run, run_study(run, workers=workers)))
    return out


def study_lines(results) -> list[str]:
    lines = ["| study | run | designs | optimum | GII | paper | ratio | time (s) |",
             "| --- | --- | ---: | --- | ---: | ---: | ---: | ---: |"]
    for platform, run, res in results:
        design = run.design_display(res.top_designs[:1])
        text = ", ".join(f"{k} {v[0]:g}" for k, v in design.items())
        value = float(res.top_values[0])
        label = "" if run.series_value is None else f"{run.series.key.split('.')[-1]} = {run.series_value:g}"
        lines.append(f"| `{STUDIES[platform]}` | {label} | {run.n_designs:,} | {text} | {_fmt(value, 4)} | "
                     f"{PAPER[platform]:g} | {_fmt(value / PAPER[platform], 3)} | {res.wall_seconds:.0f} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--table2", action="store_true", help="also evaluate on Table II's 4,492,488 poses (minutes)")
    ap.add_argument("--studies", action="store_true", help="also run the three reduced studies (minutes)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes for --studies")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    table = rows(with_table2=args.table2)
    print(markdown(table))
    print()
    for r in table:
        extra = "" if r.table2 is None else f"; Table II: {r.table2.reached:,} of {r.table2.poses:,} poses reached"
        print(f"- {r.label}: coarse {r.coarse.reached:,} of {r.coarse.poses:,} poses reached{extra}")
    if args.studies:
        print()
        print("\n".join(study_lines(run_studies(args.workers))))
    print(f"\n({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
