"""Mechanism models: forward and inverse kinematics, Jacobians, limits. numpy only.

The public face: the ``Mechanism`` contract, the models and their parameters, the registry of
kinds, task-space grids, and unit conversion between SI and display units (mm, deg).

>>> from kinematics import FiveBar, mechanism_class
>>> mechanism_class("fivebar") is FiveBar
True

Each public name is imported from its module on first use (PEP 562 ``__getattr__``): importing
one module (``kinematics.grid``) does not import every model.
"""
from __future__ import annotations

from .lazy import public_names

#: Module of this package -> the public names it gives the package.
_PUBLIC = {
    "arrays": ("BoolArray", "FloatArray"),
    "contract": ("Mechanism",),
    "base": ("MechanismBase", "ParamInfo"),
    "fivebar": ("DEXTEROUS_ANNULUS", "FiveBar", "FiveBarParams", "Singularity"),
    "delta": ("Delta", "DeltaParams"),
    "inverse3": ("Inverse3", "Inverse3Params"),
    "inoue": ("InoueParams", "InouePlatform"),
    "serial_rrr": ("SerialRRR", "SerialRRRParams"),
    "stewart": ("StewartParams", "StewartPlatform"),
    "twin_pantograph": ("TwinPantograph", "TwinPantographParams"),
    "grid": ("GridSpec",),
    "registry": ("MECHANISMS", "kind_of", "mechanism_class"),
    "units": ("joint_display_units", "joints_from_si", "joints_to_si", "task_display_units", "task_from_si",
              "task_to_si"),
}
_HOME = {name: module for module, names in _PUBLIC.items() for name in names}

__all__ = list(_HOME)


__getattr__, __dir__ = public_names(__name__, _HOME)
