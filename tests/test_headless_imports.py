"""The compute layer imports no GUI or plotting library (DESIGN.md, "Layers").

Checked in a fresh interpreter: other tests may import Qt into this process.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Every module of the headless packages, found at run time so new modules are covered too.
SCRIPT = r"""
import importlib, pkgutil, sys
names = []
for package in ("kinematics", "metrics", "resources"):
    pkg = importlib.import_module(package)
    names.append(package)
    for info in pkgutil.walk_packages(pkg.__path__, package + "."):
        importlib.import_module(info.name)
        names.append(info.name)
import metrics.quantities, metrics.workspace, kinematics.fivebar, kinematics.inverse3
for required in ("metrics.quantities", "metrics.workspace", "metrics.polytopes", "kinematics.inverse3"):
    assert required in names, required
banned = {"PySide6", "pyvista", "pyvistaqt", "vtk", "vtkmodules", "matplotlib", "shiboken6", "PyQt5", "PyQt6"}
loaded = sorted({m.split(".")[0] for m in sys.modules} & banned)
assert not loaded, f"headless packages pulled in {loaded}"
print(len(names), "modules")
"""


def test_compute_layer_imports_no_gui_or_plotting_library():
    result = subprocess.run([sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert int(result.stdout.split()[0]) >= 10


def test_the_check_itself_can_fail():
    """The same check flags a banned module when one is imported (json stands in for Qt)."""
    script = SCRIPT.replace('"PySide6",', '"PySide6", "json",').replace(
        "import metrics.quantities,", "import json, metrics.quantities,")
    result = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode != 0
    assert "headless packages pulled in ['json']" in result.stderr
