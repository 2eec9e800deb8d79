"""How a device is loaded: which torque rating, and gravity (a mounting orientation) or none.

A ``Loading`` is a small frozen description that the quantity graph (``metrics.quantities``),
maps (``metrics.workspace.compute_map``) and poses (``metrics.pose.analyse_pose``) take as
``loading=``. It selects the rated joint-torque limits ``t`` (``"continuous"``:
``Mechanism.torque_limits``, the default; ``"peak"``: ``Mechanism.peak_torque_limits``) and,
with gravity on, supplies the per-pose torque bias ``b(q) = Mechanism.gravity_torque(q, g)``
(N m, the torque the joints spend holding the links). The force set is then
``{f : -t - b <= J^T f <= t - b}``, a shifted parallelepiped (or zonotope), and every force
quantity is computed on it (``metrics.torque_box.torque_range``). ``Loading()`` (continuous,
gravity off) gives the unloaded numbers bit for bit.

Examples
--------
>>> from kinematics.serial_rrr import SerialRRR
>>> loading = Loading.mounted("upright", rating="peak")
>>> loading.describe()
'peak rating, gravity upright (0, 0, -9.80665) m/s^2'
>>> loading.torque_limits(SerialRRR()).round(4).tolist()
[1.7157, 1.4448, 1.4448]
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.gravity import MOUNTINGS, check_gravity, gravity_vector

from .torque_box import TorqueSet

#: The torque ratings a device may have; ``"continuous"`` always exists (``torque_limits``).
RATINGS = ("continuous", "peak")


class LoadingError(ValueError):
    """A loading the mechanism cannot take; ``argument`` is ``"rating"`` or ``"gravity"``."""

    def __init__(self, argument: str, message: str) -> None:
        super().__init__(message)
        self.argument = argument


@dataclass(frozen=True)
class Loading:
    """A torque rating and, optionally, gravity in the device's base frame.

    Attributes
    ----------
    rating : str
        ``"continuous"`` (``Mechanism.torque_limits``) or ``"peak"`` (``peak_torque_limits``).
    gravity : tuple of 3 float or None
        Gravity in the base frame, m/s^2; ``None``: gravity off (no bias).
    mounting : str or None
        The ``kinematics.gravity.MOUNTINGS`` name ``gravity`` came from, for labels; ``None``
        for a vector given directly (or gravity off).
    """

    rating: str = "continuous"
    gravity: tuple[float, float, float] | None = None
    mounting: str | None = None

    def __post_init__(self) -> None:
        if self.rating not in RATINGS:
            raise ValueError(f"rating must be one of {', '.join(RATINGS)}, got {self.rating!r}")
        if self.mounting is not None:
            vector = gravity_vector(self.mounting)       # raises naming the mounting
            if self.gravity is None:
                object.__setattr__(self, "gravity", vector)
        if self.gravity is not None:
            object.__setattr__(self, "gravity", check_gravity(self.gravity))

    @classmethod
    def mounted(cls, mounting: str, *, rating: str = "continuous") -> "Loading":
        """Gravity of a named mounting orientation (``kinematics.gravity.MOUNTINGS``), standard g.

        Parameters
        ----------
        mounting : str
            E.g. ``"upright"``, ``"inverted"``, ``"x-up"``.
        rating : str
            One of ``RATINGS``.

        Returns
        -------
        Loading
        """
        return cls(rating=rating, mounting=mounting)

    @property
    def biased(self) -> bool:
        """Gravity is on: the force set is shifted by a per-pose torque bias.

        Returns
        -------
        bool
        """
        return self.gravity is not None

    def check(self, mechanism, *, device: str | None = None) -> None:
        """Raise a ValueError, naming the device and the argument, if ``mechanism`` cannot be loaded so.

        Parameters
        ----------
        mechanism : Mechanism
            The model.
        device : str, optional
            How to name the device (a preset key); default the model's class name.

        Raises
        ------
        LoadingError
            A ``ValueError`` whose ``argument`` is ``"rating"`` (a peak rating asked of a model
            without one) or ``"gravity"`` (gravity asked of a model without a mass model).
        """
        name = device or type(mechanism).__name__
        if self.rating == "peak" and mechanism.peak_torque_limits() is None:
            raise LoadingError("rating", f"rating 'peak': {name} has no peak torque rating (its source gives "
                                         f"one torque per actuator, the continuous rating)")
        if self.biased and not mechanism.has_mass_model:
            raise LoadingError("gravity", f"gravity: {name} has no mass model (link masses and centres of "
                                          f"mass), so no gravity torque")

    def torque_limits(self, mechanism) -> FloatArray:
        """The rated joint-side limits ``t`` (n,), N m (N for a prismatic joint).

        Parameters
        ----------
        mechanism : Mechanism
            The model.

        Returns
        -------
        ndarray, shape (n,)

        Raises
        ------
        ValueError
            For ``"peak"`` on a model without a peak rating.
        """
        if self.rating == "continuous":
            return mechanism.torque_limits()
        peak = mechanism.peak_torque_limits()
        if peak is None:
            self.check(mechanism)
        return np.asarray(peak, float)

    def torque_set(self, mechanism) -> TorqueSet:
        """The rated limits as a ``TorqueSet``, validated once for a pose or a map (no bias yet:
        the graph's ``torque_bias`` node adds it, ``TorqueSet.with_bias``).

        Parameters
        ----------
        mechanism : Mechanism
            The model.

        Returns
        -------
        TorqueSet
        """
        return TorqueSet.of(self.torque_limits(mechanism), n=mechanism.n_joints)

    def torque_bias(self, mechanism, q: ArrayLike) -> FloatArray | None:
        """The torque the joints spend holding the links at ``q`` (..., n), N m; ``None`` with gravity off.

        Parameters
        ----------
        mechanism : Mechanism
            The model (with a mass model when gravity is on).
        q : array_like, shape (..., n)
            Actuated joints.

        Returns
        -------
        ndarray, shape (..., n), or None
        """
        if not self.biased:
            return None
        return mechanism.gravity_torque(q, self.gravity)

    def as_dict(self) -> dict[str, Any]:
        """Plain values for JSON: ``rating``, ``gravity`` (``"off"`` or mounting and vector).

        Returns
        -------
        dict

        Examples
        --------
        >>> Loading().as_dict()
        {'rating': 'continuous', 'gravity': 'off'}
        >>> Loading(gravity=(0.0, 9.81, 0.0)).as_dict()["gravity"]
        {'mounting': None, 'vector': [0.0, 9.81, 0.0], 'unit': 'm/s^2', 'frame': 'base'}
        """
        gravity: Any = "off"
        if self.biased:
            gravity = {"mounting": self.mounting, "vector": list(self.gravity), "unit": "m/s^2", "frame": "base"}
        return {"rating": self.rating, "gravity": gravity}

    def describe(self) -> str:
        """One phrase for a report: ``"continuous rating, gravity off"``.

        Returns
        -------
        str
        """
        if not self.biased:
            return f"{self.rating} rating, gravity off"
        vector = "(" + ", ".join(f"{v:g}" for v in self.gravity) + ") m/s^2"
        where = f"{self.mounting} {vector}" if self.mounting else f"{vector} in the base frame"
        return f"{self.rating} rating, gravity {where}"


#: Continuous rating, gravity off: the unloaded numbers.
DEFAULT_LOADING = Loading()

__all__ = ["DEFAULT_LOADING", "MOUNTINGS", "RATINGS", "Loading", "LoadingError"]
