"""Print paper 001's orientation sample counts (eq. 16) and check its workspace totals.

Usage, from the repository root::

    python scripts/orientation_samples.py                    # 45 and 30 deg, N = 1..15
    python scripts/orientation_samples.py --bounds 45 --max-rings 30

For each tip bound it prints K_r for N = 1.. under both floor rules of
``metrics.orientations`` ("exact": what fits in real arithmetic; "float": eq. 16 evaluated
literally in double precision, as the paper evidently did) and which terms are exact
integers. Then it checks the text's example {6, 8, 34, 58} and the totals of Tables II
and VI, including the choice of N by eq. 15. ``tests/metrics/test_orientations.py``
asserts the same numbers.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from metrics import orientations as O  # noqa: E402


def factorise(value: int) -> str:
    """Prime factorisation as text, e.g. 2^2 * 3^3 * 5 * 17^3."""
    parts, p, rest = [], 2, value
    while p * p <= rest:
        power = 0
        while rest % p == 0:
            rest //= p
            power += 1
        if power:
            parts.append(f"{p}^{power}" if power > 1 else f"{p}")
        p += 1
    if rest > 1:
        parts.append(str(rest))
    return " * ".join(parts)


def count_table(bound_deg: float, max_rings: int) -> list[str]:
    tb = math.radians(bound_deg)
    lines = [f"K_r (eq. 16) for tip bound {bound_deg:g} deg",
             f"{'N':>3} {'exact':>6} {'float':>6}  exact-integer terms (n: value)"]
    for big_n in range(1, max_rings + 1):
        exact = O.rotation_count(tb, big_n, rule="exact")
        flt = O.rotation_count(tb, big_n, rule="float")
        terms = O.ring_terms(tb, big_n)
        hits = [f"n={n}: {x:.17g}" for n, x in enumerate(terms, start=1)
                if abs(x - round(x)) <= O.INTEGER_TOL * max(1.0, x)]
        mark = "  <- differ" if exact != flt else ""
        lines.append(f"{big_n:>3} {exact:>6} {flt:>6}  {', '.join(hits) or '-'}{mark}")
    return lines


def paper_checks() -> list[str]:
    out = []
    t45, t30 = math.radians(45.0), math.radians(30.0)

    def check(label: str, ok: bool) -> None:
        out.append(f"[{'ok' if ok else 'MISMATCH'}] {label}")

    # Text after eq. 16: "for 45 deg, K_r can be chosen from {6, 8, 34, 58, ...} for N = 1, 2, 3, 4".
    flt = [O.rotation_count(t45, n, rule="float") for n in range(1, 5)]
    exact = [O.rotation_count(t45, n) for n in range(1, 5)]
    terms2 = np.floor(O.ring_terms(t45, 2)).astype(int).tolist()
    out.append("Text after eq. 16, 45 deg, N = 1..4: paper {6, 8, 34, 58}")
    out.append(f"  float rule {flt}, exact rule {exact}")
    check(f"N = 2: 1 + {terms2[0]} + {terms2[1]} = {flt[1]}; the text's 8 is a damaged 18", flt[1] == 18)
    check("N = 3: the paper's 34 is the float rule (24 sin(30 deg) floors to 11 in double); exact gives 35",
          flt[2] == 34 and exact[2] == 35)
    check("N = 1 and N = 4: 6 and 58 under both rules", flt[0] == exact[0] == 6 and flt[3] == exact[3] == 58)

    # Table II: i -8..8 (17), j, k -5..5 (11 each) at 1 cm; i,k tip bound 30 deg, 168; roll j 13.
    out.append("")
    out.append("Table II (6-DOF, +-30 deg): positions 17 x 11 x 11, tip directions 168, roll 13")
    positions = 17 * 11 * 11
    target = O.balanced_rotation_count((17, 11, 11), 2)
    n_float = O.choose_ring_count(t30, target, rule="float")
    k_float = O.rotation_count(t30, n_float, rule="float")
    k_exact = O.rotation_count(t30, n_float)
    out.append(f"  eq. 15: k_r = (17*11*11)^(2/3) = {target:.1f}; closest K_r at N = {n_float}: "
               f"{k_float} (float), {k_exact} (exact)")
    check("tip directions 168 = K_r(30 deg, N = 7) under the float rule (exact rule: 169)", k_float == 168)
    roll = len(O.roll_angles(math.radians(30.0), 13))
    total = positions * k_float * roll
    check(f"total 17*11*11 * 168 * 13 = {total:,} (table: 4,492,488); roll -30..30 deg step 5 = 13; "
          f"the table's j row 'Max -30 deg' is damaged", total == 4_492_488)
    out.append(f"  with the exact rule the total would be {positions * k_exact * roll:,}")
    half = 9 * 11 * 11 * k_float * roll
    out.append("  text: 'minimum position on the i axis set to 0 so the total is 2,653,020'")
    out.append(f"  i = 0..8 cm is 9 samples: 9*11*11 * 168 * 13 = {half:,}")
    out.append(f"  2,653,020 = {factorise(2_653_020)}: no factor 7, 11 or 13, so it is not a product "
               f"with 11 samples on j or k, 168 tips or 13 rolls")
    check("2,653,020 does not reproduce (no product of the table's counts gives it)", half == 2_653_020)

    # Table VI: i 0..8 (17), j 0..5 (11), k -5..5 (21) at 0.5 cm; tip bound 45 deg, 617; no roll.
    out.append("")
    out.append("Table VI (5-DOF, +-45 deg): positions 17 x 11 x 21 (a quarter), tip directions 617")
    full = O.balanced_rotation_count((33, 21, 21), 2)
    quarter = O.balanced_rotation_count((17, 11, 21), 2)
    n_full = O.choose_ring_count(t45, full, rule="float")
    n_quarter = O.choose_ring_count(t45, quarter, rule="float")
    k_full = O.rotation_count(t45, n_full, rule="float")
    out.append(f"  eq. 15 on the full grid 33*21*21 (W of eq. 25 at 0.5 cm): k_r = {full:.1f} -> N = {n_full}, "
               f"K_r = {k_full} (exact rule {O.rotation_count(t45, n_full)})")
    out.append(f"  eq. 15 on the quarter 17*11*21: k_r = {quarter:.1f} -> N = {n_quarter}, "
               f"K_r = {O.rotation_count(t45, n_quarter, rule='float')}: the paper sized the rotations "
               f"on the full workspace")
    check("617 = K_r(45 deg, N = 14), both rules", k_full == 617 == O.rotation_count(t45, 14))
    total6 = 17 * 11 * 21 * k_full
    check(f"total 17*11*21 * 617 = {total6:,} (table: 2,422,959)", total6 == 2_422_959)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bounds", type=float, nargs="+", default=[45.0, 30.0], help="tip bounds in degrees")
    parser.add_argument("--max-rings", type=int, default=15, help="largest N to print")
    args = parser.parse_args(argv)
    for bound in args.bounds:
        print("\n".join(count_table(bound, args.max_rings)))
        print()
    print("\n".join(paper_checks()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
