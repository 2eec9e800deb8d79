"""Mechanism models: forward and inverse kinematics, Jacobians, limits. numpy only."""
from .base import BoolArray, FloatArray, Mechanism, MechanismBase, ParamInfo
from .fivebar import FiveBar, FiveBarParams, Singularity
from .inverse3 import Inverse3, Inverse3Params
from .stewart import StewartParams, StewartPlatform
from .twin_pantograph import TwinPantograph, TwinPantographParams

__all__ = [
    "BoolArray", "FloatArray", "Mechanism", "MechanismBase", "ParamInfo",
    "FiveBar", "FiveBarParams", "Singularity", "Inverse3", "Inverse3Params",
    "StewartParams", "StewartPlatform", "TwinPantograph", "TwinPantographParams",
]
