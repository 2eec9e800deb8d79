"""The box of joint torques: its corners (sign patterns) and its usable range ``[lo, hi]``.

Every force set in ``metrics`` is the image of a box of joint torques: the parallelepiped
``{f : lo <= J^T f <= hi}`` (``metrics.parallelepiped``, ``metrics.isotropy``,
``metrics.anisotropy``) and the zonotope ``A [lo, hi]`` (``metrics.zonotopes``). This module
says what the box is, and nothing about J:

- ``sign_patterns``: its ``2^n`` corners as sign vectors, in the order every vertex list follows;
- ``torque_range``: the usable range ``lo = torque_min - b <= tau <= hi = torque_limits - b``
  from asymmetric limits and a torque bias ``b`` (as in pycapacity's
  ``force_polytope(J, t_max, t_min, t_bias)``: the bias is torque the joints already spend);
- ``asymmetric_range``: which code path a force-set function takes for given limits;
- ``TorqueSet``: the box validated once (limits, bias, range), which every force-set function
  takes as its ``torque_limits`` as it is; ``torque_set`` builds it at a public boundary.

Where neither ``torque_min`` nor ``torque_bias`` is given, or the range comes out centred
(``lo == -hi`` everywhere), the symmetric code runs unchanged (bit-identical numbers).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from kinematics.validation import validate_actuator_limits

from .linalg import as_jacobian


def sign_patterns(n: int, *, half: bool = False) -> FloatArray:
    """All ``2^n`` sign vectors (rows, shape (2^n, n)); ``half`` keeps one of each +-pair.

    Parameters
    ----------
    n : int
        Number of actuators.
    half : bool
        Keep only the rows with a positive first entry (``2^(n-1)`` rows).

    Returns
    -------
    ndarray, shape (2^n, n), or (2^(n-1), n) with ``half``
        Entries +-1.0, in ``itertools.product((1.0, -1.0), repeat=n)`` order.

    Examples
    --------
    >>> sign_patterns(2).tolist()
    [[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]]
    >>> sign_patterns(3, half=True).shape
    (4, 3)
    """
    rows = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    return rows[rows[:, 0] > 0] if half else rows


def _finite_torques(name: str, values: ArrayLike, n: int) -> FloatArray:
    """Finite per-actuator torques broadcastable to ``(..., n)`` (any sign), or raise naming ``name``."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}) to match the Jacobian's {n} columns, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


@dataclass(frozen=True, eq=False)
class TorqueSet:
    """The usable joint-torque box ``lo <= tau <= hi`` of one evaluation, validated once.

    Built by ``TorqueSet.of`` (or ``torque_set``) at a public boundary, or by
    ``metrics.loading.Loading.torque_set`` at the entry of a pose or a map; every force-set
    function then takes it as its ``torque_limits`` as it is, with no second check. The derived
    arrays are computed on first use and kept.

    Attributes
    ----------
    limits : ndarray, shape (..., n)
        Rated limits ``t``, positive and finite (with ``minimum``: the upper limit, finite), N m.
    bias : ndarray, shape (..., n), or None
        Torque the joints already spend ``b`` (gravity), N m; None: 0.
    minimum : ndarray, shape (..., n), or None
        Lower limits, below ``limits``, N m; None: ``-limits``.
    """

    limits: FloatArray
    bias: FloatArray | None = None
    minimum: FloatArray | None = None

    @classmethod
    def of(cls, torque_limits: ArrayLike, *, n: int, torque_min: ArrayLike | None = None,
           torque_bias: ArrayLike | None = None) -> "TorqueSet":
        """Validate plain limits once, naming the argument that is wrong (``torque_range``'s checks).

        Parameters
        ----------
        torque_limits : array_like, shape (..., n)
            Upper limits ``t``, N m; positive when ``torque_min`` is not given.
        n : int
            Number of actuators (columns of J).
        torque_min : array_like, shape (..., n), optional
            Lower limits below ``torque_limits``, N m; default ``-torque_limits``.
        torque_bias : array_like, shape (..., n), optional
            Torque already spent, N m; default 0.

        Returns
        -------
        TorqueSet

        Raises
        ------
        ValueError
            For a wrong shape, a non-finite value, a non-positive limit, or ``t_min >= t_max``.

        Examples
        --------
        >>> box = TorqueSet.of([1.0, 2.0], n=2, torque_bias=[0.5, 0.0])
        >>> box.lower.tolist(), box.upper.tolist(), box.nearer.tolist()
        ([-1.5, -2.0], [0.5, 2.0], [0.5, 2.0])
        """
        if torque_min is None:
            hi = validate_actuator_limits(torque_limits, name="torque_limits", n=n)
            lo = None
        else:
            hi = _finite_torques("torque_limits", torque_limits, n)
            lo = _finite_torques("torque_min", torque_min, n)
            if not np.all(lo < hi):
                raise ValueError(f"torque_min must be below torque_limits for every actuator, got torque_min = "
                                 f"{lo.tolist()} and torque_limits = {hi.tolist()}")
        b = None if torque_bias is None else _finite_torques("torque_bias", torque_bias, n)
        return cls(hi, b, lo)

    def with_bias(self, bias: FloatArray | None) -> "TorqueSet":
        """The same limits shifted by ``bias`` (..., n), N m, taken as it is (a computed gravity torque).

        Parameters
        ----------
        bias : ndarray, shape (..., n), or None

        Returns
        -------
        TorqueSet
        """
        return replace(self, bias=bias)

    @cached_property
    def shifted(self) -> bool:
        """A minimum or a bias was given: the shifted code paths (and their clamps to 0) apply."""
        return self.minimum is not None or self.bias is not None

    @cached_property
    def lower(self) -> FloatArray:
        """``lo = t_min - b`` (..., n), broadcast with ``upper``, N m."""
        return self._range[0]

    @cached_property
    def upper(self) -> FloatArray:
        """``hi = t - b`` (..., n), broadcast with ``lower``, N m."""
        return self._range[1]

    @cached_property
    def _range(self) -> tuple[FloatArray, FloatArray]:
        hi = self.limits
        lo = -hi if self.minimum is None else self.minimum
        if self.bias is not None:
            with np.errstate(over="ignore"):
                lo, hi = lo - self.bias, hi - self.bias
        lo, hi = np.broadcast_arrays(lo, hi)
        return lo, hi

    @cached_property
    def centred_limits(self) -> FloatArray | None:
        """The ``t`` of the symmetric code path: ``limits`` when nothing shifts the set, ``upper``
        when the range comes out centred (``lo == -hi`` everywhere), None when it is off-centre."""
        if not self.shifted:
            return self.limits
        return self.upper if np.array_equal(self.lower, -self.upper) else None

    @cached_property
    def half_width(self) -> FloatArray:
        """``(hi - lo) / 2`` (..., n): the half-edges' torques of the (shifted) set, N m."""
        return 0.5 * (self.upper - self.lower)

    @cached_property
    def nearer(self) -> FloatArray:
        """``t - |b|`` (..., n): each slab's nearer face (``limits`` without a bias), N m."""
        return self.limits if self.bias is None else self.limits - np.abs(self.bias)

    @cached_property
    def unbiased(self) -> "TorqueSet":
        """The rated set without its bias (what the reference forces and ellipsoids are of)."""
        return self if self.bias is None else replace(self, bias=None)

    @cached_property
    def per_unit(self) -> "TorqueSet":
        """The set in units of the rated limits, limits 1 and bias ``b / t``: for sets built on ``A diag(t)``."""
        ones = np.ones(np.shape(self.limits)[-1])
        return TorqueSet(ones, None if self.bias is None else self.bias / self.limits)


def torque_set(torque_limits, *, n: int, torque_min: ArrayLike | None = None,
               torque_bias: ArrayLike | None = None) -> TorqueSet:
    """A force-set function's ``torque_limits`` as a ``TorqueSet``: a set passes as it is, plain
    arrays are validated once (``TorqueSet.of``).

    Parameters
    ----------
    torque_limits : TorqueSet or array_like, shape (..., n)
        The set, or upper limits ``t``, N m.
    n : int
        Number of actuators (columns of J).
    torque_min, torque_bias : array_like, shape (..., n), optional
        As ``TorqueSet.of``; not accepted with a ``TorqueSet`` (it holds its own).

    Returns
    -------
    TorqueSet

    Raises
    ------
    ValueError
        As ``TorqueSet.of``, or for ``torque_min``/``torque_bias`` given beside a ``TorqueSet``.

    Examples
    --------
    >>> box = torque_set([1.0, 2.0], n=2)
    >>> torque_set(box, n=2) is box, box.shifted
    (True, False)
    """
    if isinstance(torque_limits, TorqueSet):
        if torque_min is not None or torque_bias is not None:
            raise ValueError("torque_min and torque_bias are part of a TorqueSet: pass them to TorqueSet.of")
        return torque_limits
    return TorqueSet.of(torque_limits, n=n, torque_min=torque_min, torque_bias=torque_bias)


def torque_range(torque_limits: ArrayLike, *, n: int, torque_min: ArrayLike | None = None,
                 torque_bias: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
    """Usable joint-torque range ``[torque_min - torque_bias, torque_limits - torque_bias]``.

    As in pycapacity's ``force_polytope(J, t_max, t_min, t_bias)``: the bias is torque the
    joints already spend (a preload, gravity compensation), so the force set is
    ``{f : lo <= J^T f <= hi}``.

    Parameters
    ----------
    torque_limits : array_like, shape (..., n)
        Upper joint torque limits ``t_max``, N m. Positive when ``torque_min`` is not given.
    n : int
        Number of actuators (columns of J).
    torque_min : array_like, shape (..., n), optional
        Lower limits ``t_min < t_max``, N m; default ``-torque_limits``.
    torque_bias : array_like, shape (..., n), optional
        Torque already spent ``b``, N m; default 0.

    Returns
    -------
    lo, hi : ndarray, shape (..., n)
        ``t_min - b`` and ``t_max - b``, broadcast to one shape, N m.

    Raises
    ------
    ValueError
        Naming the argument, for a wrong shape, a non-finite value, or ``t_min >= t_max``.

    Examples
    --------
    >>> lo, hi = torque_range([2.0, 3.0], n=2, torque_min=[-1.0, -3.0], torque_bias=[0.5, 0.0])
    >>> lo.tolist(), hi.tolist()
    ([-1.5, -3.0], [1.5, 3.0])
    """
    box = TorqueSet.of(torque_limits, n=n, torque_min=torque_min, torque_bias=torque_bias)
    return box.lower, box.upper


def asymmetric_range(jac: ArrayLike | None, norms: ArrayLike | None, torque_limits: ArrayLike,
                     torque_min: ArrayLike | None, torque_bias: ArrayLike | None):
    """``None`` for the symmetric fast path, an array ``t`` for a centred range, else ``(lo, hi)``.

    ``TorqueSet.centred_limits`` for plain arrays (the force-set functions read the set itself);
    the arguments are those of ``metrics.isotropy.facet_distances`` (``jac`` or its column
    ``norms``, shape (..., n)).

    A range that comes out centred (``lo == -hi`` everywhere) takes the fast path with
    ``t = hi``: its numbers are the symmetric ones, bit for bit.

    Parameters
    ----------
    jac : array_like, shape (..., m, n), or None
        Jacobians; only its number of columns is read, and only when ``norms`` is None.
    norms : array_like, shape (..., n), or None
        Column norms of J; only the number of columns is read.
    torque_limits : array_like, shape (..., n)
        Joint torque limits (the upper limit with ``torque_min``), N m.
    torque_min : array_like, shape (..., n), or None
        Lower joint torque limits, N m; None: ``-torque_limits``.
    torque_bias : array_like, shape (..., n), or None
        Torque the joints already spend, N m; None: 0.

    Returns
    -------
    None, ndarray of shape (..., n), or tuple of two such ndarrays
        None when neither ``torque_min`` nor ``torque_bias`` is given; ``t = hi`` when the
        range is centred; else ``(lo, hi)`` (``torque_range``), N m.

    Raises
    ------
    ValueError
        As ``torque_range``.

    Examples
    --------
    >>> asymmetric_range(np.eye(2), None, [1.0, 2.0], None, None) is None
    True
    >>> asymmetric_range(np.eye(2), None, [1.0, 2.0], [-1.0, -2.0], None).tolist()
    [1.0, 2.0]
    >>> [a.tolist() for a in asymmetric_range(None, [1.0, 1.0], [1.0, 2.0], None, [0.5, 0.0])]
    [[-1.5, -2.0], [0.5, 2.0]]
    """
    if torque_min is None and torque_bias is None:
        return None
    n = (np.shape(norms) if norms is not None else as_jacobian(jac).shape)[-1]
    box = TorqueSet.of(torque_limits, n=n, torque_min=torque_min, torque_bias=torque_bias)
    return (box.lower, box.upper) if box.centred_limits is None else box.centred_limits
