"""Whole-process time of ``isoforce figure`` against the floors of the libraries it renders with.

Usage, from the repository root::

    python scripts/bench_figures.py                    # inverse3_prototype, 5 rounds, a table
    python scripts/bench_figures.py novint_falcon --rounds 3 --json

Each round runs, as fresh processes with no display (as on a server; ``DISPLAY`` unset) and in
turn, so that load on a shared machine falls on all of them alike:

- ``vtk floor``: one sphere rendered off-screen by VTK alone and written to PNG (no PyVista,
  no matplotlib): what any VTK figure costs to start, load its libraries and make a GL context;
- ``pyvista floor``: the same sphere through a PyVista ``Plotter``, composed by a matplotlib
  ``Figure`` (the two libraries ``isoforce figure`` draws a 3D view with; PyVista 0.49 imports
  ``matplotlib.pyplot`` itself when its plotting module loads);
- ``pose`` and ``workspace``: ``isoforce figure DEVICE --view pose`` and ``--view workspace``;
- ``pose,workspace,map``: the three views in one run (``--out .../x_{view}.png``), and its time
  per figure;
- with ``--with DEVICE2``: ``6 separate runs`` (each of the three views of each device in a
  process of its own, one after another, timed together) against ``one run, 2 devices`` (the
  same six figures from one ``isoforce figure DEVICE DEVICE2 --view pose,workspace,map --out
  .../{device}_{view}.png``).

It prints the median wall and CPU (user + system, the child's) seconds of each over the rounds.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics as pystats
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

VTK_FLOOR = """
import sys
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL backend's factories)
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow,
                                         vtkWindowToImageFilter)
sphere = vtkSphereSource()      # kept: an output port does not keep its producer alive
mapper = vtkPolyDataMapper(); mapper.SetInputConnection(sphere.GetOutputPort())
actor = vtkActor(); actor.SetMapper(mapper)
renderer = vtkRenderer(); renderer.AddActor(actor)
window = vtkRenderWindow(); window.SetOffScreenRendering(1); window.AddRenderer(renderer)
window.SetSize(1600, 1200); window.Render()
grab = vtkWindowToImageFilter(); grab.SetInput(window); grab.Update()
writer = vtkPNGWriter(); writer.SetFileName(sys.argv[1]); writer.SetInputConnection(grab.GetOutputPort())
writer.Write()
"""

PYVISTA_FLOOR = """
import sys
import pyvista as pv
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
plotter = pv.Plotter(off_screen=True, window_size=(1600, 1200))
plotter.add_mesh(pv.Sphere())
image = plotter.screenshot(return_img=True)
figure = Figure(figsize=(16, 12), dpi=100)
FigureCanvasAgg(figure)
figure.add_axes((0, 0, 1, 1)).imshow(image)
figure.savefig(sys.argv[1])
"""


VIEWS = ("pose", "workspace", "map")


def _commands(device: str, out: Path, second: str | None = None) -> dict[str, tuple[list, int]]:
    """Each measured command (an argv, or a list of argvs run one after another) and how many figures it writes."""
    isoforce = [sys.executable, "-c", "import sys; from app.launch import main; sys.exit(main(sys.argv[1:]))"]
    pair = {}
    if second is not None:
        pair = {
            "6 separate runs": ([[*isoforce, "figure", d, "--view", v, "--out", str(out / f"sep_{d}_{v}.png")]
                                 for d in (device, second) for v in VIEWS], 6),
            "one run, 2 devices": ([*isoforce, "figure", device, second, "--view", ",".join(VIEWS),
                                    "--out", str(out / "one_{device}_{view}.png")], 6),
        }
    return pair | {
        "vtk floor": ([sys.executable, "-c", VTK_FLOOR, str(out / "vtk.png")], 1),
        "pyvista floor": ([sys.executable, "-c", PYVISTA_FLOOR, str(out / "pyvista.png")], 1),
        "pose": ([*isoforce, "figure", device, "--view", "pose", "--out", str(out / "pose.png")], 1),
        "workspace": ([*isoforce, "figure", device, "--view", "workspace", "--out", str(out / "workspace.png")], 1),
        "pose,workspace,map": ([*isoforce, "figure", device, "--view", "pose,workspace,map",
                                "--out", str(out / "all_{view}.png")], 3),
    }


def _run(argv: list, env: dict, cwd: Path = ROOT) -> tuple[float, float]:
    """Wall and CPU seconds of one process (or of several, one after another) run in ``cwd``; raise with
    its stderr if it fails."""
    if argv and isinstance(argv[0], list):
        runs = [_run(one, env, cwd) for one in argv]
        return sum(w for w, _ in runs), sum(c for _, c in runs)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    result = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode:
        raise SystemExit(f"{' '.join(argv[:4])} ... failed:\n{result.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("device", nargs="?", default="inverse3_prototype")
    parser.add_argument("--rounds", type=int, default=5, help="runs of each command (default 5)")
    parser.add_argument("--with", dest="second", metavar="DEVICE2",
                        help="also time the three views of DEVICE and DEVICE2 as six runs and as one")
    parser.add_argument("--only-pair", action="store_true", help="with --with: time only those two")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"     # no X attempt (and no warning) in the floors
    with tempfile.TemporaryDirectory() as folder:
        commands = _commands(args.device, Path(folder), args.second)
        if args.only_pair:
            commands = {k: v for k, v in commands.items() if k in ("6 separate runs", "one run, 2 devices")}
        times = {name: [] for name in commands}
        for _ in range(args.rounds):
            for name, (command, _) in commands.items():
                times[name].append(_run(command, env))
    result = {}
    for name, runs in times.items():
        figures = commands[name][1]
        wall = pystats.median(w for w, _ in runs)
        cpu = pystats.median(c for _, c in runs)
        result[name] = {"figures": figures, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                        "wall_per_figure_s": round(wall / figures, 3), "runs_wall_s": [round(w, 3) for w, _ in runs]}
    if args.json:
        print(json.dumps({"device": args.device, "with": args.second, "rounds": args.rounds, "load": os.getloadavg()[0],
                          "commands": result}))
        return 0
    print(f"{args.device}: median of {args.rounds} rounds, whole processes, no display "
          f"(load average {os.getloadavg()[0]:.2f})")
    print(f"{'command':<22}{'wall s':>9}{'CPU s':>9}{'wall s / figure':>17}   runs (wall s)")
    for name, r in result.items():
        each = ", ".join(f"{w:.2f}" for w, _ in times[name])
        print(f"{name:<22}{r['wall_s']:>9.3f}{r['cpu_s']:>9.3f}{r['wall_per_figure_s']:>17.3f}   {each}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
