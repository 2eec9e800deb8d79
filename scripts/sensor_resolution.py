"""Paper 001's sensor-resolution design (eqs. 23-27, Table IX, Fig. 15) in our reconstruction.

Usage, from the repository root::

    python scripts/sensor_resolution.py                        # table + docs/sensor_resolution.png
    python scripts/sensor_resolution.py --out /tmp/fig15.svg   # PNG, SVG or PDF by suffix
    python scripts/sensor_resolution.py --no-force             # sensor study only (about 2 s)
    python scripts/sensor_resolution.py --no-force --diagnose  # and where each GII is set

Two stages, as in the paper. (1) The force GII study ``twin_pantograph_distance`` (Table
VIII; about 45 s), run here with 10 cm added, gives the force-optimal design and its force
GII at each distance. (2) The shipped study ``twin_pantograph_sensor`` finds the optimal
waist/shoulder sensor-resolution ratio ``R_w/R_s`` of each of those designs by the sensor GII
(``metrics.sensor_gii.velocity_gii``). The sensor study file holds the stage-1 designs as data;
this script checks that they are what stage 1 finds and stops (exit 1) if not, so the file
cannot silently go stale. It prints a table next to Table IX (``paper_data.TABLE9_*``) and
Table VIII's GIIs (the distance study's ``paper`` figures), and writes the Fig. 15-like plot
(force GII and sensor GII against distance, ours and the paper's) through
``app.plots.figures.save_figure`` (atomic). ``docs/sensor_resolution.md`` explains the comparison.
"""
from __future__ import annotations

import argparse
import copy
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from matplotlib.figure import Figure  # noqa: E402

from app.files.export import FIGURE_SUFFIXES, check_output  # noqa: E402
from app.plots.figures import save_figure  # noqa: E402
from metrics.design import build_study, run_study  # noqa: E402
from resources import load_study  # noqa: E402
from resources.study_schema import study_from_data  # noqa: E402
from scripts.paper_data import TABLE9_DISTANCES_CM, TABLE9_GII, TABLE9_RATIO  # noqa: E402

SENSOR_STUDY = "twin_pantograph_sensor"
FORCE_STUDY = "twin_pantograph_distance"
GEOMETRY = ("shoulder_separation", "upper_arm", "forearm", "pen_length")
DEFAULT_OUT = ROOT / "docs" / "sensor_resolution.png"


def _best(run) -> tuple[dict[str, float] | None, float]:
    """The optimum's display values and objective value; ``(None, nan)`` if no design reaches."""
    res = run_study(run, top_k=1)
    if not res.top_designs.size or not math.isfinite(res.top_values[0]):
        return None, float("nan")
    disp = run.design_display(res.top_designs[:1])
    return {k: float(v[0]) for k, v in disp.items()}, float(res.top_values[0])


def sensor_rows() -> list[dict]:
    """One row per distance of the sensor study: distance (cm), geometry (mm), ratio, GII."""
    study = build_study(load_study(SENSOR_STUDY))
    rows = []
    for run in study.runs():
        best, value = _best(run)
        p = run.mechanism.params
        rows.append({"distance": run.series_value / 10.0, "ratio": None if best is None else best["Q1"],
                     "sensor_gii": value, "geometry": tuple(round(getattr(p, g) * 1e3, 6) for g in GEOMETRY)})
    return rows


def force_rows(distances_mm: list[float]) -> dict[float, dict]:
    """Stage 1: the force GII study at these distances (mm): optimum geometry (mm) and GII, per cm."""
    spec = load_study(FORCE_STUDY)
    data = copy.deepcopy(spec.raw)
    paper = dict(zip(data["series"]["values"], data["series"]["paper"]))
    data["series"]["values"] = list(distances_mm)
    data["series"].pop("paper", None)
    study = build_study(study_from_data(data, spec.source, spec.key))
    out = {}
    for run in study.runs():
        best, value = _best(run)
        geometry = None if best is None else tuple(best[g] for g in GEOMETRY)
        out[run.series_value / 10.0] = {"geometry": geometry, "force_gii": value,
                                        "paper": paper.get(run.series_value)}
    return out


def check_designs(sensor: list[dict], force: dict[float, dict]) -> list[str]:
    """Where the sensor study's designs are not stage 1's optima (empty: they all are)."""
    problems = []
    for row in sensor:
        f = force[row["distance"]]
        if f["geometry"] is None:
            if row["ratio"] is not None:
                problems.append(f"{row['distance']:g} cm: the force study finds no design, the sensor study one")
        elif tuple(f["geometry"]) != row["geometry"]:
            problems.append(f"{row['distance']:g} cm: the sensor study has {row['geometry']}, the force study's "
                            f"optimum is {f['geometry']} ({', '.join(GEOMETRY)}, mm)")
    return problems


def diagnose() -> str:
    """Where each optimum's sensor GII is set: how much rotation the weakest and the strongest
    normalised hand velocity hold, and the isotropy of the translation and rotation columns alone."""
    import numpy as np

    from metrics import sensor_gii as SG
    from metrics.design.evaluators import hand_velocities

    study = build_study(load_study(SENSOR_STUDY))
    lines = ["| distance (cm) | R_w/R_s | sensor GII | rotation share, weakest | rotation share, strongest | "
             "GII of translation columns | GII of rotation columns |", "|" + "---|" * 7]
    for run in study.runs():
        best, value = _best(run)
        if best is None:
            continue
        mech, x = run.mechanism, run.workspace.points
        q, _ = mech.inverse(x)
        k = np.swapaxes(mech.force_map(q, x), -1, -2)
        r = best["Q1"] * np.array([1, 0, 0, 1, 0, 0]) + np.array([0, 1, 1, 0, 1, 1])
        m = SG.velocity_scaled_matrix(k, r, hand_velocities(run))
        _, sv, vt = np.linalg.svd(m)
        lo, hi = int(np.argmin(sv[:, -1])), int(np.argmax(sv[:, 0]))
        share = [float(np.sum(vt[lo, -1, 3:] ** 2)), float(np.sum(vt[hi, 0, 3:] ** 2))]
        parts = [np.linalg.svd(m[..., cols], compute_uv=False) for cols in (slice(0, 3), slice(3, None))]
        iso = [float(p[:, -1].min() / p[:, 0].max()) for p in parts]
        lines.append(f"| {run.series_value / 10:g} | {best['Q1']:.2f} | {value:.3f} | {share[0]:.3f} | "
                     f"{share[1]:.3f} | {iso[0]:.3f} | {iso[1]:.3f} |")
    return "\n".join(lines)


def _fmt(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}f}"


def table(sensor: list[dict], force: dict[float, dict] | None) -> str:
    """Markdown table: ours next to Table IX (and Table VIII's force GII when stage 1 ran)."""
    paper = {d: (r, g) for d, r, g in zip(TABLE9_DISTANCES_CM, TABLE9_RATIO, TABLE9_GII)}
    head = ["distance (cm)", "R_w/R_s paper", "R_w/R_s ours", "sensor GII paper", "sensor GII ours"]
    if force is not None:
        head += ["force GII paper (VIII)", "force GII ours"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in sensor:
        d = row["distance"]
        p_ratio, p_gii = paper.get(d, (None, None))
        ours_gii = row["sensor_gii"] if row["ratio"] is not None else None
        cells = [f"{d:g}", _fmt(p_ratio, 2), _fmt(row["ratio"], 2), _fmt(p_gii),
                 _fmt(ours_gii) if ours_gii is not None else "no design reaches"]
        if force is not None:
            f = force[d]
            cells += [_fmt(f["paper"]) if f["paper"] is not None else "not printed",
                      _fmt(f["force_gii"]) if f["geometry"] is not None else "no design reaches"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def figure(sensor: list[dict], force: dict[float, dict] | None) -> Figure:
    """Fig. 15-like: GII (dimensionless) against workspace distance (cm); solid force, dashed sensor."""
    fig = Figure(figsize=(6.4, 4.2), dpi=150, layout="constrained")
    ax = fig.add_subplot()
    ok = [r for r in sensor if r["ratio"] is not None]
    ax.plot([r["distance"] for r in ok], [r["sensor_gii"] for r in ok], "o--", color="C1",
            label="sensor GII, ours (eqs. 23-27)")
    ax.plot(TABLE9_DISTANCES_CM, TABLE9_GII, "s--", color="C1", alpha=0.45, mfc="none",
            label="sensor GII, paper (Table IX)")
    if force is not None:
        fk = sorted(d for d, f in force.items() if f["geometry"] is not None)
        ax.plot(fk, [force[d]["force_gii"] for d in fk], "o-", color="C0", label="force GII, ours (eq. 11)")
        pk = sorted(d for d, f in force.items() if f["paper"] is not None)
        ax.plot(pk, [force[d]["paper"] for d in pk], "s-", color="C0", alpha=0.45, mfc="none",
                label="force GII, paper (Table VIII)")
    none = [r["distance"] for r in sensor if r["ratio"] is None]
    if none:
        ax.plot(none, [0.0] * len(none), "x", color="k", ms=8, label="no design reaches the workspace")
    ax.set_xlabel("workspace distance from the base along k (cm)")
    ax.set_ylabel("GII (dimensionless)")
    ax.set_title("Twin-Pantograph: GII against workspace position (cf. paper 001 Fig. 15)", fontsize=10)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    return fig


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="figure file (.png, .svg or .pdf)")
    parser.add_argument("--diagnose", action="store_true",
                        help="also print where each optimum's sensor GII is set (rotation vs translation)")
    parser.add_argument("--no-force", action="store_true",
                        help="skip stage 1 (the force study, ~45 s): no force curve, designs not checked")
    args = parser.parse_args(argv)
    try:
        check_output(args.out, FIGURE_SUFFIXES, "--out")       # before any computing
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    sensor = sensor_rows()
    t_sensor = time.perf_counter() - t0
    force = None
    if not args.no_force:
        force = force_rows([r["distance"] * 10.0 for r in sensor])
        t_force = time.perf_counter() - t0
        problems = check_designs(sensor, force)
        if problems:
            print("the sensor study's designs are not the force study's optima:\n  " + "\n  ".join(problems),
                  file=sys.stderr)
            return 1
    print(table(sensor, force))
    if args.diagnose:
        print("\n" + diagnose())
    path = save_figure(figure(sensor, force), args.out, name="--out")
    print(f"\nsensor study {t_sensor:.1f} s"
          + ("" if force is None else f", with the force study {t_force:.1f} s")
          + f"; figure written to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
