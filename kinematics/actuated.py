"""Limits of the actuated subset of a mechanism's joints, for models that list every joint.

The Twin-Pantograph and the Inoue platform carry per-joint parameters (``motor_torques``,
``gear_ratios``, ``motor_speeds``, ``lower_limits``, ``upper_limits``) for every joint, active or passive, and
an ``actuated`` tuple of the indices their configuration drives; both read their limits the
same way, here.
"""
from __future__ import annotations

import numpy as np

from .arrays import FloatArray
from .base import joint_side, joint_speed


class ActuatedSubset:
    """Mixin: ``torque_limits``, ``joint_speed_limits`` and ``joint_limits`` of the joints in ``self.actuated``."""

    def torque_limits(self) -> FloatArray:
        """Joint-side torque limits ``t_u = motor_torque_u * gear_ratio_u`` of the actuated joints, (n,)."""
        return joint_side(self.params.motor_torques, self.params.gear_ratios)[list(self.actuated)]

    def joint_speed_limits(self) -> FloatArray | None:
        """Joint-side speed limits ``motor_speed_u / gear_ratio_u`` of the actuated joints, (n,); None without."""
        speeds = joint_speed(self.params.motor_speeds, self.params.gear_ratios)
        return None if speeds is None else speeds[list(self.actuated)]

    def rotor_inertias(self) -> FloatArray:
        """Rotor inertia (motor side) of the actuated joints, kg m^2, (n,), from ``params.rotor_inertias``
        (one per joint, active or passive)."""
        if not self.has_mass_model:
            raise self._no_mass_model()
        return np.asarray(self.params.rotor_inertias, float)[list(self.actuated)]

    def reflected_rotor_inertias(self) -> FloatArray:
        """``J_u N_u^2`` of the actuated joints, (n,), kg m^2."""
        with np.errstate(over="ignore", under="ignore"):     # a ratio of 1e300: an unbounded rotor, inf
            return self.rotor_inertias() * np.asarray(self.params.gear_ratios, float)[list(self.actuated)] ** 2

    def joint_limits(self) -> tuple[FloatArray, FloatArray]:
        """Lower and upper limits (rad) of the actuated joints, each (n,).

        Returns
        -------
        lower, upper : ndarray, shape (n,)
            rad.
        """
        idx = list(self.actuated)
        return np.asarray(self.params.lower_limits)[idx], np.asarray(self.params.upper_limits)[idx]
