"""The one registry of mechanism kinds: the name a preset or study file gives -> the model class.

Adding a mechanism means one module in ``kinematics/``, one entry here, one preset, and
passing ``tests/kinematics/test_contract.py``.
"""
from __future__ import annotations

from .base import MechanismBase
from .delta import Delta
from .fivebar import FiveBar
from .inoue import InouePlatform
from .inverse3 import Inverse3
from .serial_rrr import SerialRRR
from .stewart import StewartPlatform
from .twin_pantograph import TwinPantograph

#: Mechanism kind (``mechanism = "..."`` in a preset) -> class.
MECHANISMS: dict[str, type[MechanismBase]] = {
    "inverse3": Inverse3,
    "fivebar": FiveBar,
    "twin_pantograph": TwinPantograph,
    "stewart": StewartPlatform,
    "delta": Delta,
    "serial_rrr": SerialRRR,
    "inoue": InouePlatform,
}


def mechanism_class(kind: str, *, name: str = "mechanism") -> type[MechanismBase]:
    """The class registered as ``kind``, or a ValueError naming ``name`` and the known kinds.

    Parameters
    ----------
    kind : str
        A key of ``MECHANISMS``.
    name : str
        What to call the argument in the error (e.g. a file's key).

    Returns
    -------
    type
        The mechanism class.

    Examples
    --------
    >>> mechanism_class("fivebar").__name__
    'FiveBar'
    """
    try:
        return MECHANISMS[kind]
    except (KeyError, TypeError):
        raise ValueError(f"{name} must be one of {', '.join(map(repr, MECHANISMS))}, got {kind!r}") from None


def kind_of(mechanism) -> str:
    """The registered kind of a mechanism instance (the inverse of ``mechanism_class``).

    Parameters
    ----------
    mechanism : Mechanism
        An instance of a class in ``MECHANISMS`` (not of a subclass).

    Returns
    -------
    str
        Its key in ``MECHANISMS``.

    Raises
    ------
    ValueError
        If its class is not registered.

    Examples
    --------
    >>> kind_of(FiveBar())
    'fivebar'
    """
    for kind, cls in MECHANISMS.items():
        if type(mechanism) is cls:
            return kind
    raise ValueError(f"mechanism must be one of the registered kinds {', '.join(MECHANISMS)}, "
                     f"got {type(mechanism).__name__}")
