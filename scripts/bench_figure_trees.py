"""Before and after: ``isoforce figure`` run from two source trees, whole commands, interleaved.

Usage, from the repository root::

    git archive main | tar -x -C /tmp/before        # the tree to compare with (any checkout)
    python scripts/bench_figure_trees.py /tmp/before .            # pose and workspace, 3 rounds
    python scripts/bench_figure_trees.py /tmp/before . --views pose --rounds 5 --device fivebar_singh

Each round runs, for each view, ``python -m app.cli figure DEVICE --view VIEW --out ...`` once
from each tree in turn (a fresh process, ``PYTHONPATH`` and the working directory the tree, no
display), so that load on a shared machine falls on both alike. It prints each run's wall and
CPU (user + system) seconds as it goes, then per view and tree the runs, their medians and the
load average (``uptime``'s 1-minute figure) before and after: on a loaded machine the CPU seconds
move less than the wall seconds. Last, it compares the PNG each tree wrote for each view of the
last round pixel by pixel (``pixels equal``, or the count of differing pixels and the largest
channel difference).

Each tree runs its own code against the same interpreter and libraries; its compiled map kernels
are cached in its own ``__pycache__``, so run each tree once before timing it (a first run
compiles them). The interpreter writes no bytecode when ``PYTHONDONTWRITEBYTECODE`` is set: then
every run compiles the tree's own modules from source, and the time includes that.
"""
from __future__ import annotations

import argparse
import os
import statistics as pystats
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_figures import _run as timed_run  # noqa: E402  (scripts/ beside this one)


def _run(tree: Path, device: str, view: str, out: Path) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of one ``isoforce figure`` process from ``tree``; raise
    with its stderr if it fails."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = str(tree)
    return timed_run([sys.executable, "-m", "app.cli", "figure", device, "--view", view, "--out", str(out)], env,
                     tree)


def _difference(a: Path, b: Path) -> str:
    """``"pixels equal"``, or how two PNGs differ (size, or differing pixels and the largest difference)."""
    from matplotlib.image import imread

    x, y = imread(a), imread(b)
    if x.shape != y.shape:
        return f"sizes differ: {x.shape} and {y.shape}"
    differ = (x != y).any(axis=-1)
    if not differ.any():
        return "pixels equal"
    return (f"{int(differ.sum())} of {differ.size} pixels differ, largest channel difference "
            f"{float(abs(x - y).max()) * 255:.0f}/255")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("before", type=Path, help="the source tree to compare with")
    parser.add_argument("after", type=Path, help="the source tree measured")
    parser.add_argument("--device", default="inverse3_prototype")
    parser.add_argument("--views", default="pose,workspace", help="comma-separated (default pose,workspace)")
    parser.add_argument("--rounds", type=int, default=3, help="runs of each view from each tree (default 3)")
    args = parser.parse_args(argv)
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    views = [v for v in args.views.split(",") if v]
    times = {(view, name): [] for view in views for name in trees}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        outs = {(view, name): Path(folder) / f"{name}_{view}.png" for view in views for name in trees}
        for k in range(args.rounds):
            for view in views:
                for name, tree in trees.items():
                    wall, cpu = _run(tree, args.device, view, outs[view, name])
                    times[view, name].append((wall, cpu))
                    print(f"round {k + 1} {view:<10} {name:<7} wall {wall:6.2f} s  CPU {cpu:6.2f} s", flush=True)
        load_after = os.getloadavg()[0]
        print(f"\n{args.device}, whole command, {args.rounds} rounds (load average {load_before:.2f} before, "
              f"{load_after:.2f} after)")
        for view in views:
            for name in trees:
                walls, cpus = zip(*times[view, name])
                print(f"{view:<10} {name:<7} wall median {pystats.median(walls):5.2f} s (runs "
                      + ", ".join(f"{w:.2f}" for w in walls) + f")   CPU median {pystats.median(cpus):5.2f} s (runs "
                      + ", ".join(f"{c:.2f}" for c in cpus) + ")")
            print(f"{view:<10} PNG     {_difference(outs[view, 'before'], outs[view, 'after'])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
