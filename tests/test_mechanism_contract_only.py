"""Outside ``kinematics/``, code asks the mechanism contract, never which model it has.

A module of ``metrics``, ``resources`` or ``app`` that names a registered model class (or the
five-bar's ``Singularity`` enum), or imports from a model's own module, guesses the mechanism:
what it needs becomes a contract member (``singularity_classes``, ``revolution``,
``dexterous_annulus``, ...) or is looked up by kind (``kind_of``, ``mechanism_class``). Names
inside docstrings and comments do not count (they describe; the AST has no names there).
"""
from __future__ import annotations

import ast
from pathlib import Path

from kinematics import MECHANISMS

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("metrics", "resources", "app")
#: Model classes by name, and the five-bar's singularity enum.
CLASS_NAMES = frozenset(cls.__name__ for cls in MECHANISMS.values()) | {"Singularity"}
#: The models' own modules (``kinematics.fivebar``, ...).
MODEL_MODULES = frozenset(cls.__module__ for cls in MECHANISMS.values())


def sniffs(source: str) -> list[tuple[int, str]]:
    """``(line, what)`` for each use of a model class or import from a model module in ``source``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Name) and node.id in CLASS_NAMES:
            found.append((node.lineno, node.id))
        elif isinstance(node, ast.Attribute) and node.attr in CLASS_NAMES:
            found.append((node.lineno, node.attr))
        elif isinstance(node, ast.ImportFrom):
            names = {a.name for a in node.names}
            if node.module in MODEL_MODULES or names & CLASS_NAMES:
                found.append((node.lineno, f"from {node.module} import {', '.join(sorted(names))}"))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, f"import {a.name}") for a in node.names if a.name in MODEL_MODULES]
    return found


def test_the_scan_finds_what_it_looks_for():
    text = ("from kinematics import FiveBar\nfrom kinematics.delta import DeltaParams\nimport kinematics.inoue\n"
            "x = isinstance(m, kinematics.TwinPantograph)\n")
    assert [line for line, _ in sniffs(text)] == [1, 2, 3, 4]
    assert sniffs('"""FiveBar in a docstring."""\n# TwinPantograph in a comment\nkind_of(m) == "fivebar"\n') == []


def test_no_module_outside_kinematics_names_a_model():
    found = [f"{path.relative_to(ROOT)}:{line}: {what}"
             for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py"))
             for line, what in sniffs(path.read_text(encoding="utf-8"))]
    assert not found, "\n".join(found)
