"""A package face whose public names are imported from their modules on first use (PEP 562).

``kinematics``, ``metrics``, ``resources`` and ``app.scenes`` each list ``name -> module`` and
take their ``__getattr__`` and ``__dir__`` from ``public_names``: importing one module of the
package (``metrics.dextrous`` for ``isoforce dextrous``) then costs that module and what it
imports, not every module the face lists.
"""
from __future__ import annotations

import importlib
import sys
from typing import Any, Callable


def public_names(package: str, homes: dict[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``, whose public names live in ``homes``' modules.

    Parameters
    ----------
    package : str
        The package's ``__name__`` (it is being imported: ``sys.modules`` holds it).
    homes : dict of str to str
        Public name -> the package's module that defines it.

    Returns
    -------
    (callable, callable)
        ``__getattr__(name)``: the name imported from its module the first time it is asked for,
        then kept in the package (a plain attribute from then on); ``__dir__()``.
    """
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str) -> Any:  # noqa: N807 (the module-level hook's name)
        module = homes.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:  # noqa: N807
        return sorted(set(namespace) | set(namespace.get("__all__", ())))

    return __getattr__, __dir__
