"""The one registry of mechanism kinds: the name a preset or study file gives -> the model class.

Adding a mechanism means one module in ``kinematics/``, one entry here, one preset, and
passing ``tests/kinematics/test_contract.py``.
"""
from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping

from .base import MechanismBase

#: Mechanism kind (``mechanism = "..."`` in a preset) -> (its module in ``kinematics``, its class).
_WHERE = {
    "inverse3": ("inverse3", "Inverse3"),
    "fivebar": ("fivebar", "FiveBar"),
    "twin_pantograph": ("twin_pantograph", "TwinPantograph"),
    "stewart": ("stewart", "StewartPlatform"),
    "delta": ("delta", "Delta"),
    "serial_rrr": ("serial_rrr", "SerialRRR"),
    "inoue": ("inoue", "InouePlatform"),
}


class _Registry(Mapping[str, type[MechanismBase]]):
    """``kind -> class`` as a read-only mapping whose classes are imported when first looked up.

    A command on one device (``isoforce dextrous twin_pantograph``) then imports its model's module
    alone, not all seven (40-90 ms of CPU). Iterating the keys or testing ``kind in MECHANISMS``
    imports nothing; ``values()`` and ``items()`` import every model.
    """

    def __getitem__(self, kind: str) -> type[MechanismBase]:
        module, name = _WHERE[kind]
        return getattr(importlib.import_module(f"{__package__}.{module}"), name)

    def __contains__(self, kind: object) -> bool:
        try:
            return kind in _WHERE
        except TypeError:       # an unhashable key is not a kind (as with a dict)
            return False

    def __iter__(self) -> Iterator[str]:
        return iter(_WHERE)

    def __len__(self) -> int:
        return len(_WHERE)

    def __repr__(self) -> str:
        return "MECHANISMS(" + ", ".join(f"{k!r}: {m}.{c}" for k, (m, c) in _WHERE.items()) + ")"


#: Mechanism kind (``mechanism = "..."`` in a preset) -> class.
MECHANISMS: Mapping[str, type[MechanismBase]] = _Registry()


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
    >>> kind_of(mechanism_class("fivebar")())
    'fivebar'
    """
    cls = type(mechanism)
    for kind, (module, name) in _WHERE.items():
        # Matched by name first: only the candidate's module is imported (it is, the instance exists).
        if cls.__module__ == f"{__package__}.{module}" and cls.__qualname__ == name and MECHANISMS[kind] is cls:
            return kind
    raise ValueError(f"mechanism must be one of the registered kinds {', '.join(MECHANISMS)}, "
                     f"got {type(mechanism).__name__}")
