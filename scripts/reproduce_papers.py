"""Reproduce paper 000 Table 3, paper 001 Table X and paper 002 Table 1 and Figs. 5 and 9, and write the report
(docs/reproduction.md, with the figures in docs/figures/).

Usage, from the repository root::

    python scripts/reproduce_papers.py                              # print the report
    python scripts/reproduce_papers.py --out docs/reproduction.md   # ... and write it
    python scripts/reproduce_papers.py --quick                      # skip the sensitivity studies

The printed tables and the comparisons with them are in ``scripts/paper_data.py``, the general
sweeps in ``metrics.sweeps``; ``tests/test_papers.py`` asserts the same numbers. The papers are
cited in ``docs/references.md``.
Progress and run times go to stderr, the report (Markdown) to stdout.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from kinematics import FiveBar  # noqa: E402
from metrics import sweeps as S  # noqa: E402
from resources import load_preset  # noqa: E402
from scripts import paper_data as P  # noqa: E402

QUANTITY_LABEL = {"condition_number": "Condition number", "anisotropic_force": "Anisotropic force (N)",
                  "isotropic_force": "Isotropic force (N)"}
QUANTITY_NAME = {"condition_number": "condition number", "anisotropic_force": "maximum anisotropic force",
                 "isotropic_force": "maximum isotropic force"}
STAT_LABEL = {"min": "min", "max": "max", "mean": "mean", "sd": "SD"}


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def cm(design) -> str:
    return "(" + ", ".join(f"{v * 100:.0f}" for v in design) + ")"


def table(header: list[str], rows: list[list[str]], align: str | None = None) -> list[str]:
    align = align or "l" + "r" * (len(header) - 1)
    rule = ["---:" if a == "r" else "---" for a in align]
    return ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"] + \
           ["| " + " | ".join(r) + " |" for r in rows]


# ------------------------------------------------------------------------------------------
def paper000(lines: list[str]) -> None:
    t0 = time.perf_counter()
    presets = [load_preset(key) for key in P.TABLE3_SCENARIOS]
    maps = S.scenario_maps([(p.mechanism, p.grid) for p in presets])
    ours = [m.stats for m in maps]
    log(f"Table 3 maps: {time.perf_counter() - t0:.1f} s")
    rows = P.compare_table3(ours)
    by_key = {(r.quantity, r.statistic, r.scenario): r for r in rows}
    grid = presets[0].grid
    lines += [
        "## Paper 000 (Łącki, Rossa, Gallacher), Table 3",
        "",
        "Inverse3 prototype as reconstructed in DESIGN.md; presets `inverse3_prototype`, `inverse3_scenario2` "
        "(g1 = 13.75) and `inverse3_scenario3` (g2 = g3 = 11.914); each preset's default map, the paper's slice: "
        f"theta_0 = 0, y = 22.3 mm, x in [-50, 350] mm, z in [-150, 500] mm, "
        f"{grid.resolution[0]} x {grid.resolution[1]} points "
        f"({maps[0].feasible_points:,} feasible). Statistics over the feasible points, SD with ddof = 1. "
        f"Acceptance: every figure within {100 * P.TABLE3_TOLERANCE:.1f} % relative; no constant was tuned.",
        "",
    ]
    header = ["Quantity", "Stat"]
    for k in range(3):
        header += [f"S{k + 1} paper", f"S{k + 1} ours", f"S{k + 1} error"]
    body = []
    for (q, s) in P.TABLE3_PAPER:
        row = [QUANTITY_LABEL[q], STAT_LABEL[s]]
        for k in range(3):
            r = by_key[(q, s, k)]
            flag = "" if r.matches else " **x**"
            row += [f"{r.paper:.3f}", f"{r.ours:.4f}", f"{100 * r.rel_error:+.3f} %{flag}"]
        body.append(row)
    lines += table(header, body, "ll" + "r" * 9)
    good = sum(r.matches for r in rows)
    worst = max((r for r in rows if r.matches), key=lambda r: abs(r.rel_error))
    lines += [
        "",
        f"**{good} of 36 figures reproduce** within 0.1 % (largest error among them "
        f"{100 * worst.rel_error:+.3f} %, {QUANTITY_NAME[worst.quantity]} {worst.statistic}, "
        f"Scenario {worst.scenario + 1}). **x** marks a figure that does not reproduce:",
        "",
    ]
    for (q, s, k), reason in P.TABLE3_MISMATCHES.items():
        r = by_key[(q, s, k)]
        lines += [f"- *{QUANTITY_LABEL[q]}, {s}, Scenario {k + 1}*: paper {r.paper:.3f}, ours {r.ours:.4f} "
                  f"({100 * r.rel_error:+.2f} %). {reason}", ""]

    mech3 = presets[2].mechanism
    sup = S.inverse3_isotropic_sup(mech3)
    t = mech3.torque_limits()
    c = mech3.params.plane_offset
    target = 11.974
    x_needed = math.sqrt((t[0] / target) ** 2 - c * c)
    h_needed = sup.h[sup.five_bar_facet >= target][0]
    lines += [
        "### Why 11.974 N is out of reach (Scenario 3, maximum isotropic force)",
        "",
        "On the slice the base joint's column of J has norm sqrt(x^2 + c^2) (c = 22.3 mm, the plane offset), and "
        "both five-bar columns have norm sqrt(a3^2 + a3'(h)^2) / 2, a function of the half-spread "
        "h = (theta_p1 - theta_p2) / 2 only. So the isotropic force is "
        "min(t0 / sqrt(x^2 + c^2), five-bar facet(h)), with t0 = 0.1 N m x 6.875 = 0.6875 N m.",
        "",
        f"- Base facet >= {target} N needs x <= {1000 * x_needed:.2f} mm.",
        f"- Five-bar facet >= {target} N (it grows with h) needs h >= {math.degrees(h_needed):.2f} deg; "
        f"Table 2's spread limit caps h at 100 deg.",
        "- For those h, theta_p1 <= 225 deg bounds theta_3 <= 135 deg - h, so x = a3 cos theta_3 >= "
        "a3(h) cos(135 deg - h); poses with theta_3 < 0 lie below the five-bar centre, where the body "
        "constraint needs x > 65 mm or z > 180 mm (then x >= 66 mm): both give a base facet below 10 N.",
        f"- The bound min(five-bar facet, base facet at that x) peaks at h = 100 deg: the corner theta_p1 = "
        f"225 deg, theta_p2 = 25 deg (x = {1000 * sup.corner_point[0]:.2f} mm, z = "
        f"{1000 * sup.corner_point[2]:.2f} mm), where the isotropic force is **{sup.corner_value:.4f} N**, the "
        f"supremum over the slice. The base joint is the bottleneck there.",
        f"- The 1000 x 1000 grid's best point gives {ours[2]['isotropic_force'].max:.4f} N at "
        f"({1000 * ours[2]['isotropic_force'].argmax[0]:.2f}, {1000 * ours[2]['isotropic_force'].argmax[2]:.2f}) "
        f"mm, next to that corner. A dense joint-space sweep (h, theta_3) finds nothing above the supremum "
        f"(tests/test_papers.py).",
        "",
        f"So no feasible point holds {target} N: it is {100 * (target / sup.sup - 1):.1f} % above the "
        "supremum under the model that reproduces the other 35 figures, including Scenario 3's mean and SD "
        "(which would move if the corner were different). The printed value and ours differ in one digit "
        "(11.**9**74 against 11.**6**74), most likely a typing or reading error in the paper.",
        "",
    ]

    lines += ["### The text's claims drawn from Table 3", "",
              "Recomputed from the paper's printed figures and from ours. A percentage holds when the printed "
              "table (within its own rounding) gives it, and ours gives it to the 0.1 % tolerance.", ""]
    body = []
    for cl in P.table3_claims(ours):
        body.append([cl.where, cl.text, f"{cl.from_paper:.2f}", f"{cl.from_ours:.2f}",
                     "holds" if cl.holds else "**does not hold**", cl.note])
    t0 = time.perf_counter()
    study = S.isotropic_force_by_gear_ratio(presets[0].mechanism, presets[0].grid, P.SECTION42_G1)
    log(f"sec. 4.2 gear-ratio study: {time.perf_counter() - t0:.1f} s")
    for cl in P.section42_claims(study, ours[1]["isotropic_force"]):
        fp = "" if math.isnan(cl.from_paper) else f"{cl.from_paper:.3f}"
        body.append([cl.where, cl.text, fp, f"{cl.from_ours:.3f}", "holds" if cl.holds else "**does not hold**",
                     cl.note])
    lines += table(["Where", "Claim", "From paper's table", "From ours", "Verdict", "Note"], body, "llrrll")
    lines += ["", "Isotropic force over the slice against the base gear ratio g1 (g2 = g3 = 5.957):", ""]
    body = [[f"{s.g1:.3f}", f"{s.g1 / 6.875 - 1:+.1%}", f"{s.g1 / 5.957:.3f}", f"{s.isotropic.min:.4f}",
             f"{s.isotropic.mean:.4f}", f"{s.isotropic.sd:.4f}", f"{s.isotropic.max:.4f}"] for s in study]
    lines += table(["g1", "vs 6.875", "g1 / g2", "min (N)", "mean (N)", "SD (N)", "max (N)"], body)
    lines += ["",
              "While the base joint is the bottleneck at the minimum, the minimum grows in proportion to g1; it "
              "stops at 3.914 N (the five-bar floor, at the 20 deg spread limit) once g1 >= 6.875 x 3.914 / 2.278 "
              "= 11.81. That is the Conclusions' \"71.8 %\"; the Discussion's \"60 %\" (g1 = 11.0, g1 / g2 = "
              "1.85) leaves the minimum at 3.65 N.", ""]


# ------------------------------------------------------------------------------------------
def paper002(lines: list[str], sensitivity: bool) -> None:
    t0 = time.perf_counter()
    sweeps = {name: P.table1_sweep(name) for name in S.SAMPLINGS}
    log(f"Table 1 sweeps: {time.perf_counter() - t0:.1f} s")
    names = list(S.SAMPLINGS)
    lines += [
        "## Paper 002 (Singh, Saha, Manivannan), Table 1",
        "",
        "Sweep a1 in 9..12 cm, a2 in 11..15 cm, a3 in 3..5 cm (1 cm steps, 60 designs); for each, the number "
        "of workspace samples with condition number K > 5 (K = inf included; unreachable samples do not "
        "count). The paper's winner is (a1, a2, a3) = (10, 15, 3) cm, tied at the minimum with (9, 14, 3) and "
        "preferred for its larger maximum inscribed circle. The paper says only that the workspace \"is "
        "divided in a set of circular arcs\", and not which working mode it used: we use \"+-\" (both elbows "
        "out) and report the other modes below. The samplings (all cell-centred, upper half plane):",
        "",
    ]
    for name, s in S.SAMPLINGS.items():
        lines.append(f"- `{name}`: {s.description}.")
    lines += ["",
              "Physical samplings count samples, so a larger workspace weighs more; the normalised ones use the "
              "paper's r_i = a_i / L, L = (a1 + a2 + a3) / 3, so (K being scale-free) they score the shape only. "
              "Arcs put the same number of points on every arc, so the density falls as 1 / radius.", ""]

    body = []
    for i, d in enumerate(sweeps[names[0]].designs):
        mic = FiveBar(proximal=d[0], distal=d[1], half_base=d[2]).max_inscribed_circle()[1]
        cells = [cm(d)]
        for n in names:
            r = sweeps[n]
            mark = "**" if r.counts[i] == r.counts.min() else ""
            cells.append(f"{mark}{r.counts[i]}{mark} ({r.ranks()[i]})")
        cells.append(f"{100 * mic:.0f}")
        body.append(cells)
    lines += ["Counts of samples with K > 5 (rank among the 60 in brackets; **bold** = minimum):", ""]
    lines += table(["(a1, a2, a3) cm"] + [f"`{n}`" for n in names] + ["r_MIC cm"], body)

    lines += ["", "### Winner under each sampling", ""]
    body = []
    for n in names:
        r = sweeps[n]
        body.append([f"`{n}`", ", ".join(cm(w) for w in r.winners()), f"{r.counts.min()}",
                     f"{r.count(P.PAPER_OPTIMUM)} ({r.rank(P.PAPER_OPTIMUM)})",
                     f"{r.count(P.PAPER_TIE)} ({r.rank(P.PAPER_TIE)})",
                     "yes" if tuple(P.PAPER_OPTIMUM) in [tuple(w) for w in r.winners()] else "no",
                     ", ".join(f"{cm(d)} {c}" for d, c in r.top(5))])
    lines += table(["Sampling", "Winner", "Count", "(10, 15, 3): count (rank)", "(9, 14, 3): count (rank)",
                    "Paper's winner?", "Top 5"], body, "llrrrll")
    lines += ["", "Kendall tau-b between the samplings' counts over the 60 designs:", ""]
    body = [[f"`{a}`"] + [f"{S.kendall_tau(sweeps[a], sweeps[b]):.3f}" for b in names] for a in names]
    lines += table(["tau"] + [f"`{n}`" for n in names], body)

    opt_pair = [sweeps["normalised_arcs"].count(P.PAPER_OPTIMUM), sweeps["normalised_arcs"].count(P.PAPER_TIE)]
    taus = [S.kendall_tau(sweeps[a], sweeps[b]) for i, a in enumerate(names) for b in names[i + 1:]]
    lines += [
        "",
        f"The samplings agree broadly (tau {min(taus):.2f} to {max(taus):.2f}: small a1, large a2, small a3 do well "
        "under all of them) "
        "but not on the winner. Only arcs in normalised lengths, which is what the paper's notation and its "
        f"Fig. 5 suggest, reproduce its result: (10, 15, 3) first with {opt_pair[0]} and (9, 14, 3) second with "
        f"{opt_pair[1]} of 27,000 samples, a near tie as the paper reports. The physical arcs make (9, 14, 3) "
        "the winner, the paper's tie partner; the physical grid favours (9, 13, 3); the normalised grid "
        "(9, 15, 5). The physical grid's count also grows with the workspace (the same box and step for "
        "every design), which penalises large designs such as (10, 15, 3) that the other samplings do not.",
        "",
    ]

    if sensitivity:
        lines += ["### Sensitivity to the sampling density", "",
                  "The same samplings with the radial/grid step doubled and halved (arcs: the angular count "
                  "halved/doubled with it):", ""]
        body = []
        t0 = time.perf_counter()
        for n in names:
            for factor in (2.0, 1.0, 0.5):
                s = S.SAMPLINGS[n]
                s2 = dataclasses.replace(s, step=s.step * factor,
                                         arc_points=int(round(s.arc_points / factor)) if s.arc_points else 0)
                r = sweeps[n] if factor == 1.0 else P.table1_sweep(s2)
                body.append([f"`{n}`", f"{factor:g}", ", ".join(cm(w) for w in r.winners()),
                             f"{r.rank(P.PAPER_OPTIMUM)}", f"{r.rank(P.PAPER_TIE)}",
                             ", ".join(f"{cm(d)} {c}" for d, c in r.top(3))])
        log(f"density sensitivity: {time.perf_counter() - t0:.1f} s")
        lines += table(["Sampling", "Step x", "Winner", "Rank (10, 15, 3)", "Rank (9, 14, 3)", "Top 3"], body,
                       "lrlrrl")
        lines += ["", "### Sensitivity to the working mode", "",
                  "\"+-\" = elbows out (ours), \"-+\" = elbows in; \"++\" and \"--\" are mirror images of each other "
                  "and give identical counts on these symmetric samplings.", ""]
        body = []
        t0 = time.perf_counter()
        for n in names:
            for mode in ("+-", "-+", "++"):
                r = sweeps[n] if mode == "+-" else P.table1_sweep(n, working_mode=mode)
                tau = S.kendall_tau(sweeps[n], r)
                body.append([f"`{n}`", f"`{mode}`", ", ".join(cm(w) for w in r.winners()),
                             f"{r.rank(P.PAPER_OPTIMUM)}", f"{r.rank(P.PAPER_TIE)}", f"{tau:.3f}"])
        log(f"working-mode sensitivity: {time.perf_counter() - t0:.1f} s")
        lines += table(["Sampling", "Mode", "Winner", "Rank (10, 15, 3)", "Rank (9, 14, 3)", "tau vs +-"], body,
                       "lllrrr")
        lines += ["",
                  "The working mode changes the answer completely (tau against \"+-\" from -0.4 to 0.2): with elbows "
                  "in or both to one side, short distal links and other base widths win, and the paper's design "
                  "ranks low. Its result is consistent with elbows out only.", ""]

    lines += ["### Maximum inscribed circle of the tied pair", ""]
    body = []
    for d in (P.PAPER_TIE, P.PAPER_OPTIMUM):
        y, r = FiveBar(proximal=d[0], distal=d[1], half_base=d[2]).max_inscribed_circle()
        y_printed = math.sqrt(r * r - (d[2] / 2) ** 2)
        body.append([cm(d), f"{100 * r:.2f}", f"{100 * y:.3f}", f"{100 * y_printed:.3f}"])
    lines += table(["(a1, a2, a3) cm", "r_MIC (cm)", "y_MIC (cm), tangent", "y_MIC (cm), formula as printed"], body)
    lines += ["",
              "r_MIC = min(a1, a2), so (10, 15, 3) has the larger circle (10 cm against 9 cm), as the paper says. "
              "Its centre is where the circle touches both legs' annuli, at distance max(a1, a2) from both base "
              "joints; the machine-read formula sqrt(r_MIC^2 - (a3/2)^2) is not tangent to them "
              "(kinematics.FiveBar.max_inscribed_circle).", ""]


def paper001(lines: list[str]) -> None:
    """Table X's derived rows from eq. 28 and its own forces; our model's spec sheet of the prototype."""
    import numpy as np

    from metrics import spec_sheet as SS

    log("paper 001 Table X ...")
    diag, apparent = SS.effective_masses(P.EQ28_D_SI)
    to_g = np.array([1e3, 1e3, 1e3, 1e7, 1e7])                       # kg -> g, kg m^2 -> g cm^2
    peak_si = np.array(P.TABLEX_PEAK) * np.array([1, 1, 1, 0.01, 0.01])
    per = np.array([SS.STANDARD_GRAVITY] * 3 + [1, 1])
    accel = SS.peak_accelerations(peak_si, diag) / per
    accel_apparent = SS.peak_accelerations(peak_si, apparent) / per
    dyn = SS.dynamic_ranges(P.TABLEX_PEAK, P.TABLEX_MINIMUM)
    axes = ["x", "y", "z", "rx", "rz"]
    header = ["Row", *(f"{a} paper" for a in axes), *(f"{a} ours" for a in axes)]
    lines += ["## Paper 001 (Stocco, Salcudean, Sassani), Table X", "",
              "The haptic pen's specification at its home position. Its derived rows follow from eq. 28's mass "
              "matrix D and Table X's own peak and minimum forces (`metrics.spec_sheet`; "
              "`tests/metrics/test_spec_sheet.py` checks each printed digit by interval arithmetic over the "
              "inputs' rounding). Effective mass is the diagonal of D: the apparent mass 1 / (D^-1)_ii differs "
              "on y and rx, which eq. 28 couples (D_24 = -346e-5), and does not give Table X's figures.", ""]
    body = [["Effective mass (g; g cm^2)", *(f"{v:g}" for v in P.TABLEX_EFFECTIVE_MASS),
             *(f"{v:.5g}" for v in diag * to_g)],
            ["Apparent mass 1/(D^-1)_ii", *([""] * 5), *(f"{v:.5g}" for v in apparent * to_g)],
            ["Peak acceleration (G; s^-2)", *(f"{v:g}" for v in P.TABLEX_PEAK_ACCEL), *(f"{v:.4g}" for v in accel)],
            ["... with the apparent mass", *([""] * 5), *(f"{v:.4g}" for v in accel_apparent)],
            ["Dynamic range (:1)", *(f"{v:g}" for v in P.TABLEX_DYNAMIC_RANGE), *(f"{v:.4g}" for v in dyn)]]
    lines += table(header, body)
    lines += table_x_geometry(header)
    lines += ["", "The other parts of paper 001 reproduced here have their own pages: the semi-dextrous "
              "workspaces of Figs. 13-14 (`docs/dextrous.md`), the sensor-resolution design of Table IX and "
              "Fig. 15 (`docs/sensor_resolution.md`), the full-size design studies of Tables II-VII "
              "(`docs/paper_scale.md`), the three platforms of Tables III-V (`docs/three_platforms.md`) and the "
              "printed claims of papers 000-002 that no table answers (`docs/printed_claims.md`).", ""]


#: Table X rows not in scripts/paper_data.py, as printed: the workspace box (cm, deg), the maximum
#: stiffness (N/cm; N cm per rad for the rotations) and damping (N s/cm; N s cm per rad).
TABLEX_WORKSPACE = (6.0, 3.75, 3.75, 45.0, 45.0)
TABLEX_MAX_STIFFNESS = (16.0, 12.0, 13.0, 874.0, 1076.0)
TABLEX_MAX_DAMPING = (0.44, 0.5, 0.36, 24.0, 30.0)
#: Table X's control rate, Hz (Sec. VI: "a tuned PD controller at a control rate of 1KHz").
TABLEX_RATE = 1000.0
SPEC = "`isoforce spec twin_pantograph_prototype`"
#: The Maxon RE 35's viscous friction, N m s/rad: K_f in RE_35.m, the source of the preset's RE 35 constants
#: (github.com/MLohoefener/Mechatronische_Systeme_Master).
RE35_VISCOUS = 6.33e-6


def _prototype_sheet(mech, x, spec, spans, *, points: int = 9, rings: int | None = None):
    """The rows `isoforce spec` prints for the prototype (``metrics.spec_sheet.spec_rows``) and its held box."""
    from metrics import spec_sheet as SS
    from metrics.resolution import mechanism_steps
    from metrics.spec_box import TABLE_X_ANGLE, TABLE_X_HALF_WIDTHS, box_orientations, largest_held_box
    from resources.spec_table import peak_torque_limits

    q, _ = mech.inverse(x[None])
    rows = SS.spec_rows(mech, x, spans=spans, peak_limits=peak_torque_limits(spec, mech),
                        steps=mechanism_steps(mech), mass_matrix=mech.task_inertia(q, x[None])[0],
                        minimum_forces=spec.minimum_forces, control_rate=spec.control_rate)
    box = largest_held_box(mech, x[:3], TABLE_X_HALF_WIDTHS, points=points,
                           orientations=box_orientations(mech, TABLE_X_ANGLE, rings=rings))
    return rows, box


def _span(values, digits: int = 2) -> str:
    """``"a-b"``: the smallest and largest of ``values`` to ``digits`` significant figures."""
    lo, hi = float(min(values)), float(max(values))
    return f"{lo:.{digits}g}-{hi:.{digits}g}"


#: Other samplings of the held box the report checks the scale on: (points per axis, eq. 16's N or None).
BOX_SAMPLINGS = ((3, None), (13, None), (5, 9), (5, 14))


def table_x_geometry(header: list[str], *, points: int = 9,
                     samplings: tuple[tuple[int, int | None], ...] = BOX_SAMPLINGS) -> list[str]:
    """Table X's rows that need the device's geometry and motors: the preset twin_pantograph_prototype's
    spec sheet (the rows `isoforce spec` prints) beside the paper's, with the rows no model gives.

    ``points`` is the held box's grid (``isoforce spec``'s default, 9); ``samplings`` are checked to give
    the same scale (four in the report; ``tests/test_reproduction_table_x.py`` passes none and a coarser
    grid, which the box's corner-limited scale does not feel)."""
    import numpy as np

    from metrics import spec_sheet as SS
    from resources.spec_table import peak_torque_limits

    preset = load_preset("twin_pantograph_prototype")
    mech, x, spec = preset.mechanism, np.array(preset.pose), preset.spec
    width = max(hi - lo for lo, hi in zip(preset.grid.lower, preset.grid.upper))
    spans = np.array([np.pi / 2 if u == "rad" else width for u in mech.task_units])   # as `spec`'s reach
    rows, box = _prototype_sheet(mech, x, spec, spans, points=points)
    peak = peak_torque_limits(spec, mech)
    cont, pk = rows["continuous"].min(axis=1), rows["peak"].min(axis=1)
    per_cm = np.array([0.01, 0.01, 0.01, 100.0, 100.0])      # N/m -> N/cm, N m/rad -> N cm/rad (and damping)
    to_si = 1.0 / per_cm
    paper_min_si = np.array(P.TABLEX_MINIMUM) * np.array([1, 1, 1, 0.01, 0.01])
    res_si = np.array(P.TABLEX_SPATIAL_RES) * np.array([1, 1, 1, np.pi / 180, np.pi / 180])
    k_paper_res = SS.quantisation_stiffness_bounds(paper_min_si, res_si) * per_cm
    b_paper = SS.sampling_damping_needed(np.array(TABLEX_MAX_STIFFNESS) * to_si, TABLEX_RATE,
                                         np.array(TABLEX_MAX_DAMPING) * to_si) * per_cm
    accel = rows["acceleration"] / np.array([SS.STANDARD_GRAVITY] * 3 + [1, 1])
    not_modelled = ["not modelled"] * 5
    body = [
        ["Workspace: box held at ±45 deg (cm; deg)", *(f"±{v:g}" for v in TABLEX_WORKSPACE),
         *(f"±{v * 100:.4g}" for v in box.half_widths), "±45", "±45", f"{SPEC}, box held at +-45 deg"],
        ["Reach through home (cm; deg)", *([""] * 5),
         *(f"{lo * 100:.4g} / +{hi * 100:.4g}" if i < 3 else f"{np.degrees(lo):.4g} / +{np.degrees(hi):.4g}"
           for i, (lo, hi) in enumerate(rows["workspace"])), f"{SPEC}, reach through the pose"],
        ["Spatial resolution (um; deg)",
         *(f"{v * 1e6:.0f}" if i < 3 else f"{v:g}" for i, v in enumerate(P.TABLEX_SPATIAL_RES)),
         *(f"{v * 1e6:.0f}" if i < 3 else f"{np.degrees(v):.3f}" for i, v in enumerate(rows["resolution"])),
         f"{SPEC}, spatial resolution"],
        ["Minimum force (N; N cm)", *(f"{v:g}" for v in P.TABLEX_MINIMUM), *not_modelled,
         "none: the preset's `[spec]` minimum_forces are the paper's"],
        ["Continuous force (N; N cm)", *(f"{v:g}" for v in P.TABLEX_CONTINUOUS),
         *(f"{v:.3g}" if i < 3 else f"{v * 100:.3g}" for i, v in enumerate(cont)), f"{SPEC}, continuous force"],
        ["Peak force (N; N cm)", *(f"{v:g}" for v in P.TABLEX_PEAK),
         *(f"{v:.3g}" if i < 3 else f"{v * 100:.3g}" for i, v in enumerate(pk)), f"{SPEC}, peak force"],
        ["Dynamic range, peak / minimum (:1)", *(f"{v:g}" for v in P.TABLEX_DYNAMIC_RANGE),
         *(f"{v:.3g}" for v in rows["dynamic_range"]), f"{SPEC}, dynamic range (peak)"],
        ["Effective mass D_ii (g; g cm^2)", *(f"{v:g}" for v in P.TABLEX_EFFECTIVE_MASS),
         *(f"{v * 1e3:.4g}" if i < 3 else f"{v * 1e7:.4g}" for i, v in enumerate(rows["effective_mass"])),
         f"{SPEC}, effective mass (D_ii)"],
        ["Peak acceleration, peak force / D_ii (G; s^-2)", *(f"{v:g}" for v in P.TABLEX_PEAK_ACCEL),
         *(f"{v:.3g}" if i < 3 else f"{v:.4g}" for i, v in enumerate(accel)), f"{SPEC}, acceleration (peak force)"],
        ["Max stiffness (N/cm; N cm/rad)", *(f"{v:g}" for v in TABLEX_MAX_STIFFNESS), *not_modelled,
         f"{SPEC}, max stiffness: not modelled"],
        ["... bound K <= 2 f_c / D, our resolution", *([""] * 5),
         *(f"{v:.3g}" for v in rows["stiffness_bound_quantisation"] * per_cm),
         f"{SPEC}, bound: stiffness K <= 2 f_c / D"],
        ["... the same bound, Table X's resolution", *([""] * 5), *(f"{v:.3g}" for v in k_paper_res),
         "`python scripts/reproduce_papers.py` (`metrics.spec_sheet.quantisation_stiffness_bounds`)"],
        ["Max damping (N s/cm; N cm s/rad)", *(f"{v:g}" for v in TABLEX_MAX_DAMPING), *not_modelled,
         f"{SPEC}, max damping: not modelled"],
        ["... b > K T / 2 + abs(B) at Table X's K and B", *([""] * 5), *(f"{v:.4g}" for v in b_paper),
         "`python scripts/reproduce_papers.py` (`metrics.spec_sheet.sampling_damping_needed`)"],
    ]
    # What limits the box at the failing corner (just past the held box): reach, a U-joint's bend or a joint limit.
    bends = np.degrees(mech.bend_angles(box.failure[None])[0])
    unit = "AB"[int(np.argmax(bends))]
    limit = np.degrees(mech.params.ujoint_limit)
    _, reached = mech.inverse(box.failure[None])
    if not reached[0]:
        why = "is out of reach (a unit's five-bar cannot place its U-joint there)"
    elif bends.max() > limit:
        why = f"bends unit {unit}'s U-joint to {bends.max():.4f} deg, past its {limit:g} deg limit"
    else:
        why = "breaks a joint limit"
    corner = ", ".join(f"{'+' if v > 0 else '-'}{a}" for a, v in zip("xyz", box.failure[:3] - x[:3]))
    turned = " and ".join(f"{np.degrees(v):+.0f} deg about {a}" for a, v in zip(("x", "z"), box.failure[3:]) if v)
    # The same scale on other samplings (the commands: --box-points N, --box-rings N).
    others = [_prototype_sheet(mech, x, spec, spans, points=n, rings=r)[1] for n, r in samplings]
    spread = max((abs(o.scale - box.scale) for o in others), default=0.0)
    grids = [(n, o) for (n, r), o in zip(samplings, others) if r is None]
    rings = [(n, r, o) for (n, r), o in zip(samplings, others) if r is not None]
    scales = ", ".join(f"{o.scale:.4f}" for o in others)
    agree = ("is the same" if spread == 0 else
             f"is the same within the bisection's {box.resolution:g} ({scales})" if spread <= box.resolution + 1e-12
             else f"is not the same ({scales})") + (
        f" on grids of {' and '.join(str(n) for n, _ in grids)} points per axis"
        + "".join(f", and on {n} with N = {r} rings ({o.orientations.count} orientations)" for n, r, o in rings)
        + " (`--box-points`, `--box-rings`)")
    if not samplings:
        agree = "was not checked on other samplings"
    motor_at_pen = [RE35_VISCOUS / arm ** 2 / 100 for arm in (0.20, 0.15)]       # N s/cm through a 20-15 cm arm
    reach = np.minimum(-rows["workspace"][:3, 0], rows["workspace"][:3, 1]) / box.half_widths
    ratio = pk / cont
    paper_ratio = np.array(P.TABLEX_PEAK) / np.array(P.TABLEX_CONTINUOUS)
    pk_cm = pk * np.array([1, 1, 1, 100, 100])
    stall = peak / mech.torque_limits()
    k_over = np.array(TABLEX_MAX_STIFFNESS) / k_paper_res
    rot_mass = rows["effective_mass"][3:] * 1e7 / np.array(P.TABLEX_EFFECTIVE_MASS[3:])
    rot_peak = pk_cm[3:] / np.array(P.TABLEX_PEAK[3:])
    accel_ratio = accel / np.array(P.TABLEX_PEAK_ACCEL)
    # Under the original reading of the pen (ujoint_lever = 0.5; the preset carries the adopted 1.0).
    original = mech.replace(ujoint_lever=0.5)
    rows2, box2 = _prototype_sheet(original, x, spec, spans, points=points)
    pk2 = rows2["peak"].min(axis=1)
    res_ratio = rows["resolution"] / res_si
    sampling = box.orientations
    lines = ["", "Rows that need the device's geometry and motors, from our reconstruction (" + SPEC + ": Table VIII's "
             "20 cm design, 4000 cpt encoders on every active joint; resolution max_u |J_iu| delta_u, "
             "`metrics.resolution`), each with the row of `isoforce spec` it comes from. The preset reads the pen as "
             "the reference-point section below adopts (`ujoint_lever = 1.0`). Our resolutions are "
             + ", ".join(f"{v:.2f}" for v in res_ratio) + " of Table X's (x, y, z, rx, rz): the paper does not "
             "define its figure, and the section below discusses the factor of about 2. The continuous forces depend "
             "on the motor torques, which the paper does not give (the preset's are estimates).", ""]
    lines += table([*header, "command, row"], body, "l" + "r" * 10 + "l")
    lines += [
        "",
        f"- **Workspace.** Table X's box (±6 x ±3.75 x ±3.75 cm at ±45 deg) is a region the pen holds at every "
        f"orientation within the bound; it is Table VI's optimization workspace (±8 x ±5 x ±5 cm at ±45 deg) "
        f"scaled by 0.75. `spec` prints the largest box of that shape centred at home that the model holds "
        f"(`metrics.spec_box`): every orientation sample reachable and feasible at every point of a "
        f"{box.points} x {box.points} x {box.points} grid over the box, corners and faces included. The "
        f"orientations are the semi-dextrous test's: {sampling.count}, eq. 16's N = {sampling.rings} rings "
        f"(K_r = {sampling.tip_count} tip directions) and the pure rotations about x and z, the roll free. The "
        f"box's scale is bisected to {box.resolution:g} of the shape. The model holds {box.scale:.3f} x Table X's "
        f"box, ±{box.half_widths[0] * 100:.2f} x ±{box.half_widths[1] * 100:.2f} x "
        f"±{box.half_widths[2] * 100:.2f} cm. A corner sets it: just beyond, the corner ({corner}) turned "
        f"{turned} {why}. The scale {agree}. The paper's box is the one it was designed for, not the largest "
        f"it holds, so a larger box is consistent with it. The reach through home holds no orientation and is "
        f"{_span(reach)} times the box's half-widths.",
        f"- **Peak force.** The preset's `[spec]` table carries a peak rating beside the continuous one: the "
        f"stall torques k_m U_N / R of the estimated Maxon motors, {peak[0]:g} N m at the waists (RE 40 148877) "
        f"and {peak[1]:g} N m at the shoulders (RE 35), each with its basis in the preset's `[source.lines]`; "
        f"the paper gives no motor torques. Peak over continuous force is "
        f"{', '.join(f'{v:.4g}' for v in ratio)} (x, y, z, rx, rz) against the paper's "
        f"{', '.join(f'{v:.2g}' for v in paper_ratio)}. On every axis the shoulders limit it is the RE 35's "
        f"stall over the preset's continuous torque, {stall[1]:.4g}, close to the paper's "
        f"{_span(paper_ratio[[0, 2, 3, 4]])} on x, z, rx and rz; the waists limit y, and their estimated ratio is "
        f"{stall[0]:.3g} (the paper's y: {paper_ratio[1]:.2g}). The peak forces themselves are "
        f"{', '.join(f'{a / b:.2f}' for a, b in zip(pk_cm, P.TABLEX_PEAK))} of the paper's: the continuous "
        f"forces' gap again, from the reading of the pen (the section below) and the unknown motors.",
        f"- **Dynamic range and peak acceleration** follow Table X's definitions, peak force over the minimum "
        f"force and over the effective mass D_ii, from the peak rating. The minimum forces are the paper's; the "
        f"masses are the model's (the eq. 28 section below compares them with the paper's). The peak "
        f"accelerations are {', '.join(f'{v:.2f}' for v in accel_ratio)} of the paper's (x, y, z, rx, rz): the "
        f"rotations' peak moments are {_span(rot_peak)} of the paper's and their masses {_span(rot_mass)}, the "
        f"translations follow their peak forces.",
        f"- **Minimum force, maximum stiffness and damping** are measured on the built pen: the static friction, "
        f"and a PD controller tuned at 1 kHz with a hand on the pen and low-pass-filtered finite-difference "
        f"velocity. No model here has friction, the hand's impedance, the filter or the tuning, so `spec` names "
        f"the three rows as not modelled. It prints instead two conditions for a passive virtual wall with the "
        f"device alone, labelled as bounds. One is K <= 2 f_c / D, encoder quantisation against Coulomb friction "
        f"(Abbott & Okamura 2005), with f_c the minimum force and D the spatial resolution. The other is "
        f"Colgate & Schenkel's b > K T / 2 + |B| for a PD wall sampled every T (paper 001's reference [5]), with "
        f"b the device's physical viscous damping. The paper does not give b, so `spec` prints the b that the "
        f"quantisation bound's K needs at T = 1 ms. Table X's stiffnesses are {_span(k_over)} times the "
        f"quantisation bound with its own resolution. Its K and B would need {_span(b_paper[:3])} N s/cm "
        f"({_span(b_paper[3:], 3)} N cm s/rad) of physical damping by Colgate & Schenkel, nearly all of it the "
        f"|B| term. A direct-drive motor's own viscous friction is far smaller: the RE 35's is "
        f"{RE35_VISCOUS:g} N m s/rad (RE_35.m, the preset's source for its constants), "
        f"{motor_at_pen[0]:.1e} to {motor_at_pen[1]:.1e} N s/cm at the pen through a 20 to 15 cm arm, "
        f"over {10 ** math.floor(math.log10(b_paper[:3].min() / motor_at_pen[1])):,} times less. Unless the "
        f"built pen had that much damping of "
        f"its own, Table X's gains are not passive with the device alone by this bound (whose velocity is a "
        f"plain backward difference; the paper's is also low-pass filtered): they were found stable with a "
        f"hand on the pen, which no device model has.",
        "",
        f"Under the original reading of the pen (U-joints l6 / 2 from its centre; "
        f"`isoforce spec twin_pantograph_prototype --set ujoint_lever=0.5`) the held box is {box2.scale:.3f} x "
        f"Table X's, and the peak moments are {pk2[3] * 100:.4g} and {pk2[4] * 100:.4g} N cm "
        f"({pk2[3] * 100 / P.TABLEX_PEAK[3]:.2f} and {pk2[4] * 100 / P.TABLEX_PEAK[4]:.2f} of the paper's), "
        f"half the adopted reading's. The peak forces along x, y and z differ by "
        f"{_span(np.abs(pk2[:3] / pk[:3] - 1) * 100)} %.",
    ]
    return lines


def paper002_figures(lines: list[str], folder: Path | None) -> None:
    """Paper 002's Figs. 5 and 9 for the preset ``fivebar_singh``: condition-number bands with the
    dexterous annulus, and the force ellipses over the isotropic-force map (written to ``folder``)."""
    import numpy as np

    from app.plots import overlays as O
    from app.render.views import export_view
    from metrics.workspace import compute_map

    log("paper 002 Figs. 5 and 9 ...")
    preset = load_preset("fivebar_singh")
    mech = preset.mechanism
    wmap = compute_map(mech, preset.grid, ("condition_number", "isotropic_force"))
    band = O.condition_bands(wmap.values["condition_number"], wmap.feasible)
    drawing = O.band_boundaries(wmap, mech)
    annulus = [text for _, _, text in drawing.rows if "annulus" in text]
    spacing = O.default_spacing(preset.grid)
    field = O.ellipse_field(mech, preset.grid, spacing, kind="force")
    mm_per_n, key = O.ellipse_scale(field)
    long = int(np.count_nonzero(field.radii[:, 0] * mm_per_n > field.spacing * 1e3))
    nx, ny = preset.grid.resolution
    lines += ["### Figs. 5 and 9: condition-number bands and force ellipses", "",
              f"The preset `fivebar_singh` (a1 = {mech.params.proximal * 1e3:g} mm, "
              f"a2 = {mech.params.distal * 1e3:g} mm, a3 = {mech.params.half_base * 1e3:g} mm) on its {nx} x {ny} "
              "grid (1 mm), "
              f"{wmap.feasible_points} feasible points. Fig. 5's bands (`app.plots.overlays.condition_bands`; "
              "`isoforce figure fivebar_singh --view bands`; in the app, View > Map overlay):", ""]
    rows = [[label, f"{np.count_nonzero(band == k)}",
             f"{100 * np.count_nonzero(band == k) / max(1, wmap.feasible_points):.2f} %"]
            for k, (label, _) in enumerate(O.BANDS)]
    rows.append(["singular, K = inf", f"{np.count_nonzero(band == O.BAND_SINGULAR)}",
                 f"{100 * np.count_nonzero(band == O.BAND_SINGULAR) / max(1, wmap.feasible_points):.2f} %"])
    lines += table(["band", "points", "share of feasible"], rows, "lrr")
    lines += ["", f"The paper's dexterous annulus, checked on this map: {annulus[0] if annulus else 'none'}.", "",
              f"Fig. 9's force ellipses every {spacing * 1e3:g} mm (`isoforce figure fivebar_singh --view "
              f"ellipses`): {len(field.radii)} regular lattice points ({len(field.radii) - long} ellipses drawn, "
              f"{long} longer than the spacing marked by triangles), {field.outside} points outside "
              f"the workspace and {field.singular} singular left out; one scale, 1 N drawn {mm_per_n:.3g} mm long "
              f"(key circle {key:g} N).",
              ""]
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        common = dict(preset=preset, mechanism=mech, workspace_map=wmap, quantity="isotropic_force")
        for what, name in (("bands", "paper002_fig5_bands.png"), ("ellipses", "paper002_fig9_force_ellipses.png")):
            path = export_view(what, folder / name, size=(1400, 900), **common)
            lines += [f"![paper 002 {what}](figures/{path.name})", ""]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="also write the report to this file (e.g. docs/reproduction.md)")
    parser.add_argument("--quick", action="store_true", help="skip the density and working-mode sensitivity studies")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    lines = [
        "# Reproducing the papers",
        "",
        "Generated by `python scripts/reproduce_papers.py --out docs/reproduction.md` from the repository root; "
        "`python -m pytest tests/test_papers.py` asserts the same figures (and the recorded mismatches, "
        "winners and rank correlations), so a change that moves them fails there first.",
        "",
    ]
    paper000(lines)
    paper001(lines)
    paper002(lines, sensitivity=not args.quick)
    paper002_figures(lines, ROOT / "docs" / "figures" if args.out is not None else None)
    text = "\n".join(lines).rstrip() + "\n"
    sys.stdout.write(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
        log(f"wrote {args.out}")
    log(f"total: {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
