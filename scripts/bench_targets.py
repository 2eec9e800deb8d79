"""Issue 25's speed targets, each measured ``--runs`` times in this process's run, with the target beside it.

Usage, from the repository root::

    python scripts/bench_targets.py                  # every row but the study, 3 runs, a table
    python scripts/bench_targets.py --json           # one JSON object
    python scripts/bench_targets.py --study          # also the full-size Table VII study (minutes a run)
    python scripts/bench_targets.py --only stewart   # the rows whose name holds "stewart"

Rows (each run a fresh process, as a user starts it, so start-up and the kernels' cache load count):

- ``map / numpy reference`` and ``map speedup vs pycapacity``: ``isoforce bench --json``'s
  ``map_1000.reference_ratio`` and ``same_jacobians.map_speedup`` (one ``bench`` run gives both);
- ``stats DEV``: ``isoforce stats DEV --json``'s ``seconds`` (the map's own clock) for every shipped preset;
- ``dextrous``: ``isoforce dextrous twin_pantograph --json``, whole command;
- ``convergence``: ``isoforce convergence inverse3_prototype``, whole command;
- ``figure pose`` / ``figure workspace``: ``isoforce figure inverse3_prototype --view ...``, whole command;
- ``figure set, per figure``: the issue's other route to cheap figures, a paper's figure set drawn by one
  ``isoforce figure`` run (``FIGURE_SET_DEVICES`` x ``--view pose,workspace,map``, nine PNGs, one start-up):
  the whole command's seconds over the number of figures it wrote;
- ``--study``: ``isoforce optimize twin_pantograph_table7 --workers 2`` (paper 001's Table VII at full
  size, 22 million designs, ``docs/paper_scale.md``), whole command.

The rows are run round by round (every row once, then again), so load on a shared machine falls
on all of them alike; the load average is printed with the table.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:        # run as a plain script from a checkout
    sys.path.insert(0, str(ROOT))

from resources import list_presets  # noqa: E402

#: (row, target, unit, lower is better): issue 25's table.
TARGETS = {"map / numpy reference": (0.05, ""), "map speedup vs pycapacity": (5000.0, "x"),
           "stats": (0.2, "s"), "dextrous twin_pantograph": (0.5, "s"), "convergence inverse3_prototype": (1.0, "s"),
           "figure pose": (1.0, "s"), "figure workspace": (1.0, "s"), "figure set, per figure": (1.0, "s"),
           "Table VII study": (60.0, "s")}
#: The devices of the ``figure set`` row: three families (a parallel arm, a serial arm, a delta).
FIGURE_SET_DEVICES = ("inverse3_prototype", "phantom_premium_15", "novint_falcon")
FIGURE_SET_VIEWS = ("pose", "workspace", "map")


def _isoforce(*args: str) -> tuple[float, str]:
    """Seconds of ``isoforce ARGS`` as a fresh process, and its stdout; raises if it fails."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "app.cli", *args], cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"isoforce {' '.join(args)} failed ({done.returncode}): {done.stderr.strip()[-400:]}")
    return seconds, done.stdout


def one_round(out_dir: Path, study: bool, only: tuple[str, ...] = ()) -> dict[str, float]:
    """Every row once (with ``only``, the rows whose name holds one of its strings): ``{row: figure}``."""
    row: dict[str, float] = {}

    def wanted(name: str) -> bool:
        return not only or any(part in name for part in only)

    if wanted("map / numpy reference") or wanted("map speedup vs pycapacity"):
        _, text = _isoforce("bench", "--json")
        bench = json.loads(text)
        row["map / numpy reference"] = bench["map_1000"]["reference_ratio"]
        if bench["same_jacobians"]["map_speedup"] is not None:
            row["map speedup vs pycapacity"] = bench["same_jacobians"]["map_speedup"]
    for key in list_presets():
        if wanted(f"stats {key}"):
            _, text = _isoforce("stats", key, "--json")
            row[f"stats {key}"] = json.loads(text)["seconds"]
    if wanted("dextrous twin_pantograph"):
        row["dextrous twin_pantograph"], _ = _isoforce("dextrous", "twin_pantograph", "--json")
    if wanted("convergence inverse3_prototype"):
        row["convergence inverse3_prototype"], _ = _isoforce("convergence", "inverse3_prototype")
    for view in ("pose", "workspace"):
        if wanted(f"figure {view}"):
            row[f"figure {view}"], _ = _isoforce("figure", "inverse3_prototype", "--view", view,
                                                 "--out", str(out_dir / f"{view}.png"))
    if wanted("figure set, per figure"):
        set_dir = out_dir / "set"
        shutil.rmtree(set_dir, ignore_errors=True)          # count this round's files only
        set_dir.mkdir()
        seconds, _ = _isoforce("figure", *FIGURE_SET_DEVICES, "--view", ",".join(FIGURE_SET_VIEWS),
                               "--out-dir", str(set_dir))
        written, expected = len(list(set_dir.glob("*.png"))), len(FIGURE_SET_DEVICES) * len(FIGURE_SET_VIEWS)
        if written != expected:
            raise RuntimeError(f"the figure set wrote {written} PNGs, not {expected}")
        row["figure set, per figure"] = seconds / written
    if study:
        row["Table VII study"], _ = _isoforce("optimize", "twin_pantograph_table7", "--workers", "2",
                                              "--out", str(out_dir / "table7.npz"))
    return row


def target_of(name: str) -> tuple[float, str]:
    """Issue 25's target of a row and its unit (``"x"``: higher is better)."""
    return TARGETS["stats"] if name.startswith("stats ") else TARGETS[name]


def table(runs: list[dict[str, float]]) -> str:
    head = f"{'row':42s} {'target':>9s} {'runs':>30s} {'median':>9s}  met"
    lines = [head, "-" * len(head)]
    for name in runs[0]:
        values = [r[name] for r in runs]
        target, unit = target_of(name)
        med = statistics.median(values)
        met = med >= target if unit == "x" else med <= target
        fmt = "{:.0f}" if unit == "x" else "{:.3f}"
        lines.append(f"{name:42s} {('>= ' if unit == 'x' else '<= ') + fmt.format(target) + unit:>9s} "
                     f"{' '.join(fmt.format(v) for v in values):>30s} {fmt.format(med):>9s}  {'yes' if met else 'no'}")
    return "\n".join(lines)


def compile_bytecode() -> None:
    """The checkout's modules compiled to bytecode first, as ``run.sh``'s install leaves them.

    A module edited since (or a checkout never installed) is otherwise read from source by every
    fresh process where ``PYTHONDONTWRITEBYTECODE`` is set (many container images set it): about
    0.15 s of CPU a command, which a user's install does not pay. Up-to-date files are skipped.
    """
    subprocess.run([sys.executable, "-m", "compileall", "-q", "-j", "0", "app", "kinematics", "metrics",
                    "resources"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="rounds over every row (default 3)")
    parser.add_argument("--study", action="store_true", help="also the full-size Table VII study (slow)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--only", nargs="+", default=(), metavar="TEXT",
                        help="only the rows whose name holds one of these, e.g. --only stewart dextrous")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error(f"--runs must be at least 1, got {args.runs}")
    compile_bytecode()
    with tempfile.TemporaryDirectory() as tmp:
        runs = [one_round(Path(tmp), args.study, tuple(args.only)) for _ in range(args.runs)]
    if not runs[0]:
        parser.error(f"--only {' '.join(args.only)} matches no row")
    load = list(os.getloadavg())
    if args.json:
        print(json.dumps({"cpus": os.cpu_count(), "load_average": load, "runs": runs,
                          "targets": {k: target_of(k)[0] for k in runs[0]}}, indent=2))
    else:
        print(f"{args.runs} rounds; {os.cpu_count()} CPUs, load average {' '.join(f'{x:.2f}' for x in load)}")
        print(table(runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
