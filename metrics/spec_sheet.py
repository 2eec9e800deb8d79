"""A device specification sheet at one pose (paper 001, Table X): the rows a datasheet prints.

Each row is per task axis (x, y, z and, for pen and platform mechanisms, the rotations):

- **force along an axis**: the largest ``t`` with ``t e_i`` in the wrench set
  ``{A tau : lo <= tau <= hi}`` (``A`` the mechanism's force map), every other wrench
  component zero: a pure force (or a pure moment) along the axis. It is read off the set's
  facets (``metrics.zonotopes``: the square case is a parallelepiped, a zonotope with
  ``n = m``), ``t = min_k h_k / (nu_k . e_i)`` over the facets that face ``+e_i`` (``-e_i``
  for the opposite direction), so it is exact, not a linear programme's tolerance.
- **spatial resolution** (``metrics.resolution``).
- **dynamic range**: peak force over the minimum force (the static friction the user must
  overcome, paper 001: "the ratio between the minimum and peak force/torque capabilities").
- **effective mass**: the diagonal ``D_ii`` of the task-space mass matrix ``D``
  (``f = D a``). Table X's figures are these diagonals: eq. 28's ``D_11 = 190e-5 N s^2/cm``
  is Table X's 190 g, and its peak accelerations are peak force over ``D_ii``
  (48 N / 0.190 kg = 25.8 G). The other common definition, the *apparent* mass
  ``1 / (D^-1)_ii`` (the mass felt when the other axes move freely), differs where ``D``
  couples axes: eq. 28 couples y with the x rotation (``D_24 = -346e-5``), which gives
  214 g against Table X's 226 g, and 9.98 G against its 9.5 G; both are reported, and
  ``tests/metrics/test_spec_sheet.py`` checks which matches.
- **peak acceleration**: peak force over ``D_ii`` (m/s^2; rad/s^2 for a rotation).

Rows the model cannot give, and the bounds it can
-------------------------------------------------
Table X's minimum force (the static friction to overcome), maximum stiffness and maximum damping
are measured on the built device: the stiffness and damping "using a tuned PD controller at a
control rate of 1 kHz with the end-point velocity computed from low-pass filtered finite
difference position readings", with a hand on the pen. No model here has friction, the hand's
impedance, the velocity filter or the tuning, so none of the three is computed. What can be
computed are two conditions for a virtual wall (a spring K and damper B) to be passive with the
device alone, each from one effect, per task axis:

- **quantisation** (``quantisation_stiffness_bounds``): ``K <= 2 f_c / Delta``. A wall computed
  from encoder counts is a staircase; over one count ``Delta`` it can release ``K Delta^2 / 2``
  that Coulomb friction ``f_c`` must dissipate, ``f_c Delta`` (Abbott and Okamura, IEEE T-RO
  21(5), 2005). ``f_c`` is the minimum force, ``Delta`` the spatial resolution.
- **sampling** (``sampling_damping_needed``, ``sampling_stiffness_bounds``): Colgate and
  Schenkel's bound for a PD wall sampled every ``T`` (paper 001's reference [5]),
  ``b > K T / 2 + |B|``, with ``b`` the device's physical viscous damping: ``K < 2 (b - |B|) / T``.

Both are sufficient conditions on the device alone (no hand holding it), not the paper's
measured figures, and are labelled as bounds wherever they are printed.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian
from .resolution import axis_resolution
from .zonotopes import zonotope

#: Standard gravity, m/s^2 (for accelerations in G, as Table X prints them).
STANDARD_GRAVITY = 9.80665


def axis_capabilities(force_map: ArrayLike, *, torque_limits: ArrayLike, torque_min: ArrayLike | None = None,
                      torque_bias: ArrayLike | None = None) -> FloatArray:
    """Largest pure wrench along each task axis, both ways, shape (m, 2): ``[:, 0]`` along ``+e_i``.

    ``t_i^+ = max {t >= 0 : t e_i in W}``, ``W = {A tau : lo <= tau <= hi}``. ``inf`` where the
    set is unbounded along the axis (``A`` not finite: a direct singularity); 0 where the
    origin is outside ``W`` (a bias the actuators cannot hold).

    Parameters
    ----------
    force_map : array_like, shape (m, n)
        ``A`` with ``w = A tau`` (``n >= m``), SI: N (N m for a moment row) per N m of torque.
    torque_limits : array_like, shape (n,)
        Upper actuator limits, N m (N for a prismatic actuator).
    torque_min : array_like, shape (n,), optional
        Lower limits, default ``-torque_limits``.
    torque_bias : array_like, shape (n,), optional
        Torque already spent (preload, gravity), default 0.

    Returns
    -------
    ndarray, shape (m, 2)
        N for force rows, N m for moment rows.

    Examples
    --------
    >>> axis_capabilities([[2.0, 0.0], [0.0, 0.5]], torque_limits=[1.0, 1.0]).tolist()
    [[2.0, 2.0], [0.5, 0.5]]
    >>> axis_capabilities([[1.0, 0.0], [0.0, 1.0]], torque_limits=[1.0, 1.0], torque_bias=[0.5, 0.0]).tolist()
    [[0.5, 1.5], [1.0, 1.0]]
    """
    a = as_jacobian(force_map, "force_map")
    if a.ndim != 2:
        raise ValueError(f"force_map must be one matrix of shape (m, n), got {a.shape}")
    m = a.shape[0]
    if not np.all(np.isfinite(a)):
        return np.full((m, 2), np.inf)
    z = zonotope(a, torque_limits=torque_limits, torque_min=torque_min, torque_bias=torque_bias)
    normals, offsets = z.normals, z.offsets
    if torque_min is None and torque_bias is None:       # symmetric: each facet pair |nu . w| <= h
        normals, offsets = np.concatenate([normals, -normals]), np.concatenate([offsets, offsets])
    keep = np.isfinite(offsets)
    normals, offsets = normals[keep], offsets[keep]
    out = np.empty((m, 2))
    for i in range(m):
        for side, sign in enumerate((1.0, -1.0)):
            facing = sign * normals[:, i]
            ahead = facing > 0
            with np.errstate(divide="ignore"):
                t = np.min(offsets[ahead] / facing[ahead]) if ahead.any() else np.inf
            out[i, side] = max(t, 0.0) if np.all(offsets >= 0) else 0.0
    return out


def effective_masses(mass_matrix: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Diagonal ``D_ii`` and apparent ``1 / (D^-1)_ii`` masses of a task-space mass matrix, each (m,).

    Parameters
    ----------
    mass_matrix : array_like, shape (m, m)
        ``D`` with ``f = D a``, symmetric positive definite, SI (kg, kg m, kg m^2).

    Returns
    -------
    diagonal, apparent : ndarray, shape (m,)
        kg for a translation, kg m^2 for a rotation.

    Raises
    ------
    ValueError
        If ``D`` is not square, symmetric (to rounding) and positive definite.

    Examples
    --------
    >>> d, app = effective_masses([[2.0, 1.0], [1.0, 2.0]])
    >>> d.tolist(), app.tolist()
    ([2.0, 2.0], [1.5, 1.5])
    """
    d = np.asarray(mass_matrix, dtype=float)
    if d.ndim != 2 or d.shape[0] != d.shape[1]:
        raise ValueError(f"mass_matrix must be square (m, m), got shape {d.shape}")
    # Symmetric to a few ulps of its largest entry: a matrix typed from a table is symmetric exactly.
    if not np.allclose(d, d.T, rtol=0.0, atol=8 * np.finfo(float).eps * np.max(np.abs(d))):
        raise ValueError("mass_matrix must be symmetric")
    try:
        np.linalg.cholesky(d)
    except np.linalg.LinAlgError:
        raise ValueError("mass_matrix must be positive definite") from None
    return np.diag(d).copy(), 1.0 / np.diag(np.linalg.inv(d))


def peak_accelerations(peak: ArrayLike, masses: ArrayLike) -> FloatArray:
    """Peak force (moment) over effective mass (inertia) per axis, shape (m,): m/s^2 or rad/s^2.

    Examples
    --------
    >>> (peak_accelerations([48.0], [0.190]) / STANDARD_GRAVITY).round(1).tolist()
    [25.8]
    """
    return np.asarray(peak, float) / np.asarray(masses, float)


def dynamic_ranges(peak: ArrayLike, minimum: ArrayLike) -> FloatArray:
    """Peak over minimum (static friction) force per axis, shape (m,), dimensionless.

    ``inf`` for a zero minimum: a device with no friction has no finite range by this measure.

    Examples
    --------
    >>> dynamic_ranges([48.0, 21.0], [0.022, 0.045]).round(0).tolist()
    [2182.0, 467.0]
    """
    with np.errstate(divide="ignore"):
        return np.asarray(peak, float) / np.asarray(minimum, float)


def quantisation_stiffness_bounds(minimum_forces: ArrayLike, resolution: ArrayLike) -> FloatArray:
    """``2 f_c / Delta`` per axis: the stiffest wall that friction keeps passive over one count, (m,).

    Parameters
    ----------
    minimum_forces : array_like, shape (m,)
        Coulomb (static) friction ``f_c`` per axis, N (N m for a rotation).
    resolution : array_like, shape (m,)
        One count's motion ``Delta`` along each axis, m (rad).

    Returns
    -------
    ndarray, shape (m,)
        N/m (N m/rad for a rotation).

    Examples
    --------
    >>> quantisation_stiffness_bounds([0.022], [142e-6]).round(1).tolist()
    [309.9]
    """
    return 2.0 * np.asarray(minimum_forces, float) / np.asarray(resolution, float)


def sampling_damping_needed(stiffness: ArrayLike, rate: float, damping: ArrayLike = 0.0) -> FloatArray:
    """Colgate and Schenkel's ``K T / 2 + |B|``: the physical damping ``b`` a sampled PD wall needs to exceed.

    Parameters
    ----------
    stiffness : array_like
        The wall's ``K``, N/m (N m/rad).
    rate : float
        The control rate ``1 / T``, Hz.
    damping : array_like
        The wall's virtual damping ``B``, N s/m (N m s/rad).

    Returns
    -------
    ndarray
        N s/m (N m s/rad).

    Examples
    --------
    >>> float(sampling_damping_needed(1600.0, 1000.0, 44.0))
    44.8
    """
    return np.asarray(stiffness, float) / (2.0 * float(rate)) + np.abs(np.asarray(damping, float))


def sampling_stiffness_bounds(physical_damping: ArrayLike, rate: float, damping: ArrayLike = 0.0) -> FloatArray:
    """Colgate and Schenkel's bound solved for the stiffness, ``K < 2 (b - |B|) / T``; 0 where ``|B| >= b``.

    Parameters
    ----------
    physical_damping : array_like
        The device's viscous damping ``b``, N s/m (N m s/rad).
    rate : float
        ``1 / T``, Hz.
    damping : array_like
        The wall's virtual damping ``B``.

    Returns
    -------
    ndarray
        N/m (N m/rad).

    Examples
    --------
    >>> sampling_stiffness_bounds([0.5, 0.5], 1000.0, [0.0, 0.2]).tolist()
    [1000.0, 600.0]
    """
    b = np.asarray(physical_damping, float)
    return np.maximum(2.0 * float(rate) * (b - np.abs(np.asarray(damping, float))), 0.0)


def axis_extents(mechanism, x: ArrayLike, spans: ArrayLike, *, samples: int = 401,
                 bisections: int = 48) -> FloatArray:
    """Feasible interval through ``x`` along each task axis, offsets from ``x``, shape (m, 2).

    Each axis is sampled at ``samples`` points over ``[-span_i, span_i]`` about ``x`` (other
    coordinates fixed); the run of feasible samples that holds ``x`` is kept and both its ends
    are bisected ``bisections`` times between the last feasible and the first infeasible sample,
    so each end is exact to ``2 span_i / (samples - 1) / 2^bisections``. A gap narrower than the
    sampling step is missed; an end at ``+-span_i`` means the interval reaches the sampled span.

    Parameters
    ----------
    mechanism : Mechanism
    x : array_like, shape (m,)
        The pose, SI; it must be feasible.
    spans : array_like, shape (m,)
        Half-width searched along each axis, SI (m; rad for a rotation).
    samples : int
        Samples per axis (odd, so that ``x`` itself is one).
    bisections : int
        Halvings of each end's bracket.

    Returns
    -------
    ndarray, shape (m, 2)
        ``[lower, upper]`` offsets, SI (lower <= 0 <= upper).

    Raises
    ------
    ValueError
        If ``x`` is not feasible, or ``samples`` is not an odd integer >= 3.
    """
    x = np.asarray(x, dtype=float)
    m = x.shape[-1]
    if samples < 3 or samples % 2 == 0:
        raise ValueError(f"samples must be an odd integer >= 3, got {samples}")

    def ok(points: FloatArray) -> np.ndarray:
        q, reach = mechanism.inverse(points)
        return reach & mechanism.feasible(q, points)

    if not ok(x[None])[0]:
        raise ValueError("the spec pose is not feasible: no workspace extent can be measured from it")
    out = np.zeros((m, 2))
    for i in range(m):
        t = np.linspace(-spans[i], spans[i], samples)
        pts = np.repeat(x[None], samples, axis=0)
        pts[:, i] += t
        good = ok(pts)
        centre = samples // 2
        for side, step in enumerate((-1, 1)):
            k = centre
            while 0 <= k + step < samples and good[k + step]:
                k += step
            if not 0 <= k + step < samples:
                out[i, side] = t[k]
                continue
            inside, outside = t[k], t[k + step]
            for _ in range(bisections):
                mid = 0.5 * (inside + outside)
                probe = x.copy()
                probe[i] += mid
                if ok(probe[None])[0]:
                    inside = mid
                else:
                    outside = mid
            out[i, side] = inside
    return out


def spec_rows(mechanism, x: ArrayLike, *, spans: ArrayLike, peak_limits: ArrayLike | None = None,
              steps: ArrayLike | None = None, mass_matrix: ArrayLike | None = None,
              minimum_forces: ArrayLike | None = None, control_rate: float | None = None,
              physical_damping: ArrayLike | None = None) -> dict[str, FloatArray]:
    """Every spec-sheet row a mechanism's data allow at pose ``x``, SI, each per task axis.

    Rows: ``workspace`` (m, 2) offsets (``axis_extents``); ``continuous`` (m, 2) pure wrench
    along ``+-e_i`` at the continuous torque limits; ``peak`` likewise with ``peak_limits``;
    ``resolution`` (m,) with joint ``steps`` (``metrics.resolution.axis_resolution``);
    ``effective_mass`` and ``apparent_mass`` (m,) from ``mass_matrix``; ``acceleration`` (m,)
    the smaller of the two directions' force (peak if given, else continuous) over the
    effective mass; ``dynamic_range`` (m,) the same force over ``minimum_forces``, which is
    itself the row ``minimum_force``. Bounds (module doc): ``stiffness_bound_quantisation``
    ``2 f_c / Delta`` (minimum forces and steps); ``damping_needed_quantisation`` the ``b > K T / 2``
    that a wall at that stiffness needs (and ``control_rate``); ``stiffness_bound_sampling``
    ``2 b / T`` and ``damping_bound_sampling`` ``b`` (``physical_damping`` and ``control_rate``: the
    largest K with B = 0, the largest |B| with K = 0). A row whose data the device does not give
    is absent.

    Parameters
    ----------
    mechanism : Mechanism
    x : array_like, shape (m,)
        A feasible pose, SI.
    spans : array_like, shape (m,)
        Half-widths searched for the workspace extents, SI.
    peak_limits : array_like, shape (n,), optional
        Peak actuator limits, N m (N for a prismatic actuator).
    steps : array_like, shape (n,), optional
        Joint sensor steps, rad (m).
    mass_matrix : array_like, shape (m, m), optional
        Task-space ``D``, SI.
    minimum_forces : array_like, shape (m,), optional
        Static friction per axis, N (N m).
    control_rate : float, optional
        The control loop's rate, Hz.
    physical_damping : array_like, shape (m,), optional
        The device's viscous damping per axis, N s/m (N m s/rad).

    Returns
    -------
    dict of str to ndarray

    Raises
    ------
    ValueError
        If ``x`` is not reachable and feasible.
    """
    x = np.asarray(x, dtype=float)
    q, reach = mechanism.inverse(x[None])
    if not (reach[0] and mechanism.feasible(q, x[None])[0]):
        raise ValueError("the spec pose is not reachable and feasible")
    a = mechanism.force_map(q, x[None])[0]
    rows: dict[str, FloatArray] = {"workspace": axis_extents(mechanism, x, spans),
                                   "continuous": axis_capabilities(a, torque_limits=mechanism.torque_limits())}
    if peak_limits is not None:
        rows["peak"] = axis_capabilities(a, torque_limits=peak_limits)
    if steps is not None:
        rows["resolution"] = axis_resolution(mechanism.jacobian(q, x[None])[0], steps)
    force = np.min(rows["peak" if peak_limits is not None else "continuous"], axis=-1)
    if mass_matrix is not None:
        rows["effective_mass"], rows["apparent_mass"] = effective_masses(mass_matrix)
        rows["acceleration"] = peak_accelerations(force, rows["effective_mass"])
    if minimum_forces is not None:
        rows["minimum_force"] = np.asarray(minimum_forces, float).copy()
        rows["dynamic_range"] = dynamic_ranges(force, minimum_forces)
        if steps is not None:
            rows["stiffness_bound_quantisation"] = quantisation_stiffness_bounds(minimum_forces, rows["resolution"])
            if control_rate is not None:
                rows["damping_needed_quantisation"] = sampling_damping_needed(rows["stiffness_bound_quantisation"],
                                                                              control_rate)
    if physical_damping is not None and control_rate is not None:
        rows["stiffness_bound_sampling"] = sampling_stiffness_bounds(physical_damping, control_rate)
        rows["damping_bound_sampling"] = np.asarray(physical_damping, float).copy()
    return rows


def weight_range(mechanism, points: ArrayLike, gravity: ArrayLike) -> tuple[float, float, int]:
    """Smallest and largest weight the hand holds over ``points``, ``|A(q) b(q)|`` in N, and the count.

    With the motors off, the hand holding the end-effector still must hold the links: the
    force ``f`` with ``J^T f = b(q)``, ``b`` the gravity torque (``Mechanism.gravity_torque``),
    i.e. ``f = A b`` with ``A`` the force map (paper 001 Table X's "Weight": "the gravitational
    force felt by the hand while holding the end-effector", over the workspace). Only the
    feasible, regular points count (at a singular one ``A`` is unbounded); the extremes are the
    grid's, so they depend on the points given.

    Parameters
    ----------
    mechanism : Mechanism
        With ``has_mass_model``.
    points : array_like, shape (k, m)
        Task points, SI.
    gravity : array_like, shape (3,)
        Gravity in the base frame, m/s^2.

    Returns
    -------
    low, high : float
        N; ``nan`` with no feasible regular point.
    count : int
        Feasible regular points used.
    """
    pts = np.asarray(points, dtype=float)
    q, reach = mechanism.inverse(pts)
    good = reach & mechanism.feasible(q, pts)
    q, pts = q[good], pts[good]
    with np.errstate(invalid="ignore", over="ignore"):
        force = np.einsum("...mn,...n->...m", mechanism.force_map(q, pts), mechanism.gravity_torque(q, gravity))
        weight = np.sqrt(np.sum(force * force, axis=-1))
    weight = weight[np.isfinite(weight)]
    if weight.size == 0:
        return float("nan"), float("nan"), 0
    return float(weight.min()), float(weight.max()), int(weight.size)
