"""Force and moment capability of devices with orientation freedoms (wrench sets).

A device whose task has orientation coordinates (Stewart platform, Twin-Pantograph) holds
wrenches ``w = (f, m)``: forces (N) on the rows whose task unit is ``"m"`` and moments
(N m) on the rows whose task unit is ``"rad"`` (``Mechanism.task_units``). A ball in the
mixed (N, N m) space means nothing, so each capability is a *slice* of the wrench set
``W = {G s : |s_u| <= 1}`` (``G = A diag(t)``, the force map's columns at full torque; for a
square ``J``, ``A = J^-T``):

=====================  ===========================================================  =====
quantity               definition                                                   unit
=====================  ===========================================================  =====
isotropic force        radius of the largest ball in ``{f : (f, 0) in W}``          N
anisotropic force      largest norm in that slice                                   N
isotropic moment       radius of the largest ball in ``{m : (0, m) in W}``          N m
anisotropic moment     largest norm in that slice                                   N m
=====================  ===========================================================  =====

How they are computed (exact up to rounding, batched)
-----------------------------------------------------
*Inscribed radius.* From the slabs (facet pairs) that bound ``W``: ``metrics.wrench_facets``
(``facets``, ``slice_inscribed_radius``; ``slice_facet_distances`` for square ``J``).

*Largest norm.* At a vertex of the slice: ``metrics.wrench_slices`` (``slice_max_norm``,
``slice_vertices``, ``hull_faces``).

Both are checked against linear programmes (scipy.optimize.linprog) in
``tests/metrics/test_wrenches.py``.

Task scaling of the condition number
------------------------------------
``J``'s rows mix m/s and rad/s, so its condition number depends on the unit of length. We
scale the rotational rows by the device's ``characteristic_length`` ``L`` (m), i.e. compare
a moment ``M`` with the force ``M / L``: ``J_s = diag(1, 1, 1, L, ...) J`` (the ``S_T`` of
paper 001 eq. 13 with all force entries 1 and all moment entries ``L``). One length for
every rotational row keeps the number independent of the base frame's orientation; paper
001's hand-based ``S_T`` (Table I: moments of 3.6, 0.5, 3.9 cm per unit force) needs the
end-effector frame and is what ``metrics.gii`` offers for the GII.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.contract import Mechanism

from .linalg import as_jacobian, singular_values


# -- which rows are forces -------------------------------------------------------------------
def force_rows(mechanism: Mechanism) -> tuple[int, ...]:
    """Rows of J (and of the wrench) that are forces: task unit ``"m"``.

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    tuple of int
        Indices into the ``m`` task coordinates.

    Examples
    --------
    >>> from kinematics.stewart import StewartPlatform
    >>> force_rows(StewartPlatform())
    (0, 1, 2)
    """
    units = tuple(mechanism.task_units)
    return tuple(i for i, u in enumerate(units) if u == "m")


def moment_rows(mechanism: Mechanism) -> tuple[int, ...]:
    """Rows of J (and of the wrench) that are moments: task unit ``"rad"``.

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    tuple of int
        Indices into the ``m`` task coordinates; ``()`` without orientation.

    Examples
    --------
    >>> from kinematics.stewart import StewartPlatform
    >>> moment_rows(StewartPlatform())
    (3, 4, 5)
    """
    units = tuple(mechanism.task_units)
    return tuple(i for i, u in enumerate(units) if u == "rad")


def characteristic_length(mechanism: Mechanism) -> float:
    """The length (m) moments are divided by to compare them with forces (``mechanism.characteristic_length``).

    Parameters
    ----------
    mechanism : Mechanism
        A model with orientation freedoms.

    Returns
    -------
    float
        m.

    Raises
    ------
    ValueError
        If the mechanism gives no positive finite length.
    """
    length = mechanism.characteristic_length
    if length is None or not (math.isfinite(float(length)) and float(length) > 0):
        raise ValueError(f"{type(mechanism).__name__} has orientation freedoms but no positive "
                         f"characteristic_length, got {length!r}")
    return float(length)


def task_row_scale(mechanism: Mechanism) -> FloatArray:
    """Diagonal of the task scaling ``S_T``, shape (m,): 1 on force rows, ``L`` on moment rows.

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    ndarray, shape (m,)
        Dimensionless on force rows, m on moment rows.

    Examples
    --------
    >>> from kinematics.stewart import StewartPlatform
    >>> task_row_scale(StewartPlatform(platform_radius=0.03)).tolist()
    [1.0, 1.0, 1.0, 0.03, 0.03, 0.03]
    """
    scale = np.ones(mechanism.task_dim)
    if mechanism.has_orientation:
        scale[list(moment_rows(mechanism))] = characteristic_length(mechanism)
    return scale


def condition_number_scaling(mechanism: Mechanism) -> dict[str, float] | None:
    """How the condition number is scaled, for output: ``{"length_m": L}``, or ``None`` (plain J).

    Parameters
    ----------
    mechanism : Mechanism
        Any model.

    Returns
    -------
    dict of str to float, or None
    """
    return {"length_m": characteristic_length(mechanism)} if mechanism.has_orientation else None


def scaled_condition_number(jac: ArrayLike, *, row_scale: ArrayLike) -> FloatArray:
    """Condition number of ``diag(row_scale) J`` (..., m, n), shape (...); ``inf`` at a singularity.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
        Jacobians.
    row_scale : array_like, shape (m,)
        Factor of each row (``task_row_scale``).

    Returns
    -------
    ndarray, shape (...)
        Dimensionless.

    Raises
    ------
    ValueError
        If ``row_scale`` does not have one entry per row.

    Examples
    --------
    >>> scaled_condition_number([[1.0, 0.0], [0.0, 4.0]], row_scale=[1.0, 0.5]).tolist()
    2.0
    """
    from .conditioning import condition_number
    jac = as_jacobian(jac)
    scale = np.asarray(row_scale, float)
    if scale.shape != jac.shape[-2:-1]:
        raise ValueError(f"row_scale must have shape ({jac.shape[-2]},), got {scale.shape}")
    with np.errstate(invalid="ignore", over="ignore"):
        scaled = jac * scale[:, None]
    return condition_number(sv=singular_values(scaled))


