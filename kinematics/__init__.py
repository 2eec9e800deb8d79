"""Mechanism models: forward and inverse kinematics, Jacobians, limits. numpy only.

The public face: the ``Mechanism`` contract, the models and their parameters, the registry of
kinds, task-space grids, and unit conversion between SI and display units (mm, deg).

>>> from kinematics import FiveBar, mechanism_class
>>> mechanism_class("fivebar") is FiveBar
True
"""
from .arrays import BoolArray, FloatArray
from .base import MechanismBase, ParamInfo
from .contract import Mechanism
from .delta import Delta, DeltaParams
from .fivebar import DEXTEROUS_ANNULUS, FiveBar, FiveBarParams, Singularity
from .grid import GridSpec
from .inoue import InoueParams, InouePlatform
from .inverse3 import Inverse3, Inverse3Params
from .registry import MECHANISMS, kind_of, mechanism_class
from .serial_rrr import SerialRRR, SerialRRRParams
from .stewart import StewartParams, StewartPlatform
from .twin_pantograph import TwinPantograph, TwinPantographParams
from .units import joint_display_units, joints_from_si, joints_to_si, task_display_units, task_from_si, task_to_si

__all__ = [
    "BoolArray", "FloatArray", "Mechanism", "MechanismBase", "ParamInfo",
    "DEXTEROUS_ANNULUS", "Delta", "DeltaParams", "FiveBar", "FiveBarParams", "Singularity",
    "Inverse3", "Inverse3Params",
    "InoueParams", "InouePlatform",
    "SerialRRR", "SerialRRRParams", "StewartParams", "StewartPlatform", "TwinPantograph", "TwinPantographParams",
    "GridSpec", "MECHANISMS", "kind_of", "mechanism_class",
    "joint_display_units", "joints_from_si", "joints_to_si", "task_display_units", "task_from_si", "task_to_si",
]
