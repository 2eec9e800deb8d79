"""What the hand feels when it moves: task-space inertia, apparent masses, acceleration capability.

============================  ==============================================  ======================
quantity                      definition                                      computed as
============================  ==============================================  ======================
task-space inertia Lambda     ``(J M^-1 J^T)^-1`` (Khatib)                     ``task_space_inertia``
mobility Lambda^-1            ``J M^-1 J^T``: acceleration per unit force     Cholesky solve, finite
                                                                              at inverse singularities
effective mass (Table X)      ``Lambda_ii``                                   ``effective_masses``
apparent mass along axis i    ``1 / (Lambda^-1)_ii``: a hand pushing along i   ``apparent_masses``
apparent-mass range           eigenvalues of ``((Lambda^-1)_tt)^-1``, force    ``apparent_mass_range``
                              rows ``t`` (a pure force, no moment)
mass condition number         largest / smallest apparent mass (dynamic       ``mass_condition_number``
                              isotropy)
acceleration set              ``{Lambda^-1 w : w in the wrench set}``         facets ``nu^T Lambda``
                              ``= {J M^-1 tau : tau in the torque box}``
isotropic acceleration        largest ball about 0 in the acceleration set    ``isotropic_acceleration``
acceleration ellipsoid        ``{J M^-1 tau : |diag(1/t) tau| <= 1}``          ``acceleration_ellipsoid``
inertia ellipsoid             semi-axes: the apparent masses along the        ``inertia_ellipsoid``
                              principal directions of ``((Lambda^-1)_tt)^-1``
============================  ==============================================  ======================

The acceleration set is the force set seen through ``Lambda^-1``: where the wrench set is the
slabs ``lo <= N w <= hi`` (``N = J^T`` for a square device), the acceleration set is
``lo <= N Lambda a <= hi``. So every force routine applies unchanged to the Jacobian ``Lambda J``
(``acceleration_jacobian``), bias and asymmetric limits included. Masses in kg, accelerations in
m/s^2; for a device with orientation freedoms the translational and rotational blocks are kept
apart (kg and kg m^2; m/s^2 at zero angular acceleration), as forces and moments are.

References: O. Khatib, "Inertial properties in robotic manipulation", IJRR 12(2), 1993;
T. Yoshikawa, "Dynamic manipulability of robot manipulators", 1985; pycapacity's
``acceleration_ellipsoid`` and ``acceleration_polytope`` (the peer the tests compare with).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .ellipsoids import Ellipsoid, _left_svd, actuator_limits
from .isotropy import isotropic_force
from .linalg import (
    SURE_REGULAR,
    _cofactors,
    components,
    outside_safe_scale,
    pow2_exponents,
    singular_values,
    symmetric_eigenvalues_3x3,
)
from .torque_box import TorqueSet


def _closed_form(mat: FloatArray) -> bool:
    """2 x 2 and 3 x 3 matrices take the entry-by-entry closed forms (``metrics.linalg``), not LAPACK."""
    return mat.shape[-2:] in ((2, 2), (3, 3))


def _psd_eigenvalues(mat: FloatArray) -> FloatArray:
    """Eigenvalues (..., m), descending, of finite symmetric positive semi-definite matrices.

    For such a matrix they are its singular values, so 2 x 2 and 3 x 3 take
    ``linalg.singular_values``' closed forms (LAPACK where those are ill-conditioned, within
    ``linalg.FAST_COND_LIMIT``'s error table); larger ones ``eigvalsh``. A rounding-negative
    eigenvalue of a singular matrix comes out as its magnitude, below the callers' null floor
    ``m eps lambda_max`` either way.
    """
    if mat.shape[-2:] == (2, 2):
        return singular_values(mat)
    if mat.shape[-2:] == (3, 3):
        return _symmetric_eigenvalues_3x3(mat)
    return np.linalg.eigvalsh(mat)[..., ::-1]


def _symmetric_eigenvalues_3x3(mat: FloatArray) -> FloatArray:
    """Eigenvalues (..., 3), descending, of finite symmetric 3 x 3 matrices: the trigonometric closed form.

    Each matrix is first scaled by a power of two (exact) to a largest entry in [0.5, 1), so the
    squares below neither over- nor underflow at any mass scale. With ``mean`` the trace / 3,
    ``p^2`` the mean square of ``A - mean I``'s entries / 6 and ``r = det(A - mean I) / (2 p^3)``,
    the eigenvalues are ``mean + 2 p cos(phi + 2 pi k / 3)``, ``phi = arccos(r) / 3``: an absolute
    error of a few ``eps`` times the largest, as LAPACK's ``eigvalsh``, except where two
    eigenvalues nearly coincide (``|r| -> 1``), where ``arccos`` loses digits
    (``eps / sqrt(1 - |r|)``); those matrices (``|r| > 1 - 1e-3``, a few per cent of a map) go
    to ``eigvalsh``. Squaring is avoided (unlike the singular values of ``linalg``, which work on
    ``A^T A``): the matrix is symmetric, so its own eigenvalues are wanted.
    """
    e = pow2_exponents(mat, axis=(-2, -1))
    a = components(np.ldexp(mat, -e[..., None, None]))
    lam1, lam2, lam3, r = symmetric_eigenvalues_3x3(a)
    out = np.stack([lam1, lam2, lam3], axis=-1)
    hard = np.abs(r) > 1.0 - 1e-3
    if np.any(hard):
        out[hard] = np.linalg.eigvalsh(np.moveaxis(a, (0, 1), (-2, -1))[hard])[..., ::-1]
    return np.ldexp(out, e[..., None])


def _inverse_closed(mat: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Adjugate inverse ``cof(A)^T / det A`` (..., n, n) of 2 x 2 / 3 x 3 matrices, and the sign of ``det A`` (...).

    A matrix whose largest entry is outside ``linalg.SAFE_SCALE`` (its cofactors and determinant,
    products of up to three entries, would over- or underflow) is inverted scaled by a power of
    two, ``A^-1 = 2^-e (2^-e A)^-1``, exactly.
    """
    scale = np.max(np.abs(mat), axis=(-2, -1))
    far = outside_safe_scale(scale) & np.isfinite(scale) & (scale > 0)
    e = pow2_exponents(mat, axis=(-2, -1)) if np.any(far) else None
    if e is not None:
        e = np.where(far, e, 0)
        mat = np.ldexp(mat, -e[..., None, None])
    a = components(mat)
    cof = _cofactors(a)
    det = sum(a[0, j] * cof[0, j] for j in range(a.shape[0]))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        inv = np.moveaxis(np.swapaxes(cof, 0, 1) / det, (0, 1), (-2, -1))
    if e is not None:
        inv = np.ldexp(inv, -e[..., None, None])
    return inv, det


def mobility(jac: ArrayLike, mass_matrix: ArrayLike) -> FloatArray:
    """``Lambda^-1 = J M^-1 J^T`` (..., m, m), m/s^2 per N: finite wherever J and M are.

    Examples
    --------
    >>> mobility(np.eye(2), 2 * np.eye(2)).tolist()
    [[0.5, 0.0], [0.0, 0.5]]
    """
    jac, mass = np.asarray(jac, float), np.asarray(mass_matrix, float)
    batch = np.broadcast_shapes(jac.shape[:-2], mass.shape[:-2])
    jac, mass = np.broadcast_to(jac, batch + jac.shape[-2:]), np.broadcast_to(mass, batch + mass.shape[-2:])
    if _closed_form(mass):
        # M^-1 by its adjugate: M is symmetric positive definite, det M > 0 wherever M is finite;
        # where rounding says otherwise, LAPACK's solve.
        inv, det = _inverse_closed(mass)
        with np.errstate(invalid="ignore", over="ignore"):
            out = jac @ inv @ np.swapaxes(jac, -1, -2)
        bad = ~(det > 0) & np.all(np.isfinite(mass), axis=(-2, -1))
        if np.any(bad):
            out[bad] = _mobility_solve(jac[bad], mass[bad])
    else:
        out = _mobility_solve(jac, mass)
    return 0.5 * (out + np.swapaxes(out, -1, -2))


def _mobility_solve(jac: FloatArray, mass: FloatArray) -> FloatArray:
    return jac @ np.linalg.solve(mass, np.swapaxes(jac, -1, -2))


def task_space_inertia(jac: ArrayLike, mass_matrix: ArrayLike) -> FloatArray:
    """Khatib's operational-space inertia ``Lambda = (J M^-1 J^T)^-1`` (..., m, m).

    ``inf`` along a direction the device cannot move in (J singular): computed from the
    eigen-decomposition of the mobility, so a zero eigenvalue gives an infinite mass.

    Parameters
    ----------
    jac : array_like, shape (..., m, n)
    mass_matrix : array_like, shape (..., n, n)
        Joint-space mass matrix, symmetric positive definite.

    Returns
    -------
    ndarray, shape (..., m, m)
        kg (length rows and columns), kg m^2 (angles).

    Examples
    --------
    >>> task_space_inertia([[1.0, 0.0], [0.0, 2.0]], np.eye(2)).round(12).tolist()
    [[1.0, 0.0], [0.0, 0.25]]
    """
    return inverse_spd(mobility(jac, mass_matrix))


def inverse_spd(mat: ArrayLike) -> FloatArray:
    """Inverse of symmetric positive semi-definite matrices (..., m, m), ``inf`` along null directions.

    Eigenvalues below ``m eps lambda_max`` (rounding of a zero) are taken as zero.
    """
    mat = np.asarray(mat, float)
    if _closed_form(mat) and mat.ndim > 2:
        # Regular matrices by the adjugate; the null ones (and non-finite) by the eigen-decomposition.
        # Most are regular beyond doubt without their eigenvalues: for a positive semi-definite
        # matrix lambda_max <= tr and lambda_min >= det / tr^(m-1), so det > SURE_REGULAR m eps tr^m
        # puts lambda_min / lambda_max above SURE_REGULAR m eps, far above the eigenvalues' rounding
        # (a few eps of lambda_max): the test below on computed eigenvalues would pass too. The
        # others (and traces whose powers could leave the floats) take that test.
        m = mat.shape[-1]
        out, det = _inverse_closed(mat)
        out = 0.5 * (out + np.swapaxes(out, -1, -2))
        tr = np.trace(mat, axis1=-2, axis2=-1)
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            # Entries within linalg.SAFE_SCALE (tr / m <= the largest <= tr), so _inverse_closed's det is
            # the matrix's own, unscaled.
            sure = ((det > SURE_REGULAR * m * np.finfo(float).eps * tr**m) & ~outside_safe_scale(tr)
                    & ~outside_safe_scale(tr / m))
        if np.all(sure):
            return out
        rest = mat[~sure]
        finite = np.all(np.isfinite(rest), axis=(-2, -1))
        w = _psd_eigenvalues(np.where(finite[..., None, None], rest, 0.0))
        regular = finite & (w[..., -1] > m * np.finfo(float).eps * w[..., 0])
        if not np.all(regular):
            sub = out[~sure]
            sub[~regular] = _inverse_spd_eigh(rest[~regular])
            out[~sure] = sub
        return out
    if mat.ndim > 2:
        return _inverse_spd_batch(mat)
    return _inverse_spd_eigh(mat)


def _inverse_spd_batch(mat: FloatArray) -> FloatArray:
    """``inverse_spd`` of a batch of m x m matrices, m > 3: Cholesky where surely regular, else eigenvalues.

    The same test as the closed forms' (``det > SURE_REGULAR m eps tr^m``, the trace and trace / m
    inside ``SAFE_SCALE``) picks the matrices whose smallest eigenvalue is far above rounding;
    those are inverted by Cholesky, compiled (``kernels.spd``: backward stable, the same ``m eps
    kappa`` relative error as the eigen-decomposition, no LAPACK call per matrix), exactly
    symmetric. The rest (null directions, non-finite or far-scaled entries) take
    ``_inverse_spd_eigh``.
    """
    from .kernels import spd

    m = mat.shape[-1]
    flat = np.ascontiguousarray(mat.reshape(-1, m, m), dtype=np.float64)
    out = np.empty_like(flat)
    sure = np.empty(len(flat), bool)
    spd.sure_inverses(flat, out, sure, np.zeros((m, m)), np.zeros((m, m)))
    if not np.all(sure):
        out[~sure] = _inverse_spd_eigh(flat[~sure])
    return out.reshape(mat.shape)


def _inverse_spd_eigh(mat: FloatArray) -> FloatArray:
    w, v = np.linalg.eigh(np.where(np.isfinite(mat), mat, 0.0))
    floor = mat.shape[-1] * np.finfo(float).eps * np.max(np.abs(w), axis=-1, keepdims=True)
    null = w <= floor
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.einsum("...ik,...k,...jk->...ij", v, np.where(null, 0.0, 1.0 / w), v)
    # A null direction adds infinity wherever its outer product is not exactly zero: an axis
    # orthogonal to it keeps a finite mass.
    touched = np.einsum("...ik,...k,...jk->...ij", np.abs(v), null.astype(float), np.abs(v)) > 0
    out = np.where(touched, np.inf, out)
    finite = np.all(np.isfinite(mat), axis=(-2, -1))
    return np.where(finite[..., None, None], out, np.nan)


def effective_masses(lam: ArrayLike) -> FloatArray:
    """``Lambda_ii`` (..., m): paper 001 Table X's effective mass along each task axis."""
    return np.diagonal(np.asarray(lam, float), axis1=-2, axis2=-1).copy()


def apparent_masses(mob: ArrayLike) -> FloatArray:
    """``1 / (Lambda^-1)_ii`` (..., m): the mass a hand pushing along axis i alone feels.

    Examples
    --------
    >>> apparent_masses([[2.0, 1.0], [1.0, 2.0]]).tolist()
    [0.5, 0.5]
    """
    diag = np.diagonal(np.asarray(mob, float), axis1=-2, axis2=-1)
    with np.errstate(divide="ignore"):
        return 1.0 / diag


def apparent_mass_range(mob: ArrayLike, rows=None) -> FloatArray:
    """Smallest and largest apparent mass over directions of a pure force on ``rows`` (..., 2), kg.

    The mass felt pushing with force ``f`` (no moment) along unit ``d`` is ``1 / d^T (Lambda^-1)_rr d``,
    so its extremes are the reciprocals of the block's eigenvalues; ``inf`` where the device
    cannot move along some direction.
    """
    mob = np.asarray(mob, float)
    if rows is not None:
        rows = list(rows)
        mob = mob[..., rows, :][..., :, rows]
    w = _psd_eigenvalues(np.where(np.isfinite(mob), mob, 0.0))                        # descending
    floor = mob.shape[-1] * np.finfo(float).eps * np.max(np.abs(w), axis=-1)
    with np.errstate(divide="ignore"):
        low = 1.0 / w[..., 0]
        high = np.where(w[..., -1] > floor, 1.0 / w[..., -1], np.inf)
    out = np.stack([low, high], axis=-1)
    finite = np.all(np.isfinite(mob), axis=(-2, -1))
    return np.where(finite[..., None], out, np.nan)


def inertia_ellipsoid(mob: ArrayLike, rows=None) -> Ellipsoid:
    """The inertia ellipsoid of a pure force on ``rows``: radii (..., r), kg, largest first, and axes (..., r, r).

    Its semi-axes lie along the principal directions of the apparent-mass matrix
    ``A = ((Lambda^-1)_rr)^-1`` (the force block of the mobility, inverted), each as long as
    the mass a hand pushing along it feels, ``1 / d^T (Lambda^-1)_rr d``: ``A``'s eigenvalue.
    So the ellipsoid's extremes are ``apparent_mass_range``. A direction the device cannot
    move along has radius ``inf`` (a zero eigenvalue of the mobility block); ``nan`` where
    the mobility is not finite.

    Examples
    --------
    >>> e = inertia_ellipsoid([[2.0, 0.0], [0.0, 0.5]])
    >>> e.radii.tolist(), np.abs(e.axes).tolist()
    ([2.0, 0.5], [[0.0, 1.0], [1.0, 0.0]])
    """
    mob = np.asarray(mob, float)
    if rows is not None:
        rows = list(rows)
        mob = mob[..., rows, :][..., :, rows]
    w, v = np.linalg.eigh(np.where(np.isfinite(mob), mob, 0.0))     # ascending: heaviest first
    floor = mob.shape[-1] * np.finfo(float).eps * np.max(np.abs(w), axis=-1, keepdims=True)
    with np.errstate(divide="ignore"):
        radii = np.where(w > floor, 1.0 / np.where(w > floor, w, 1.0), np.inf)
    finite = np.all(np.isfinite(mob), axis=(-2, -1))
    radii = np.where(finite[..., None], radii, np.nan)
    axes = np.where(finite[..., None, None], v, np.nan)
    return Ellipsoid(radii=radii, axes=axes)


def mass_condition_number(mob: ArrayLike, rows=None) -> FloatArray:
    """Largest over smallest apparent mass (..., ): 1 is dynamically isotropic, ``inf`` singular."""
    rng = apparent_mass_range(mob, rows)
    return rng[..., 1] / rng[..., 0]


def acceleration_jacobian(jac: ArrayLike, lam: ArrayLike) -> FloatArray:
    """``Lambda J`` (..., m, n): the Jacobian whose force set is the acceleration set.

    ``{a : lo <= J^T Lambda a <= hi}``: every force routine (isotropic, anisotropic, vertices,
    bias) applied to ``Lambda J`` gives the acceleration capability in m/s^2.
    """
    with np.errstate(invalid="ignore"):         # an infinite mass times a zero entry: nan, as einsum gave
        return np.matmul(np.asarray(lam, float), np.asarray(jac, float))


def isotropic_acceleration(jac: ArrayLike, lam: ArrayLike, *, torque_limits: ArrayLike | TorqueSet,
                           torque_bias: ArrayLike | None = None) -> FloatArray:
    """Largest acceleration the device reaches in every direction (..., ), m/s^2.

    The inscribed radius of ``{a : -t - b <= J^T Lambda a <= t - b}`` (``isotropy.isotropic_force``
    on ``Lambda J``); 0 where J is singular (the set is flat). ``torque_limits`` may be a
    ``TorqueSet`` (``metrics.torque_box``), taken as it is.

    Examples
    --------
    >>> float(isotropic_acceleration(np.eye(2), 2 * np.eye(2), torque_limits=[1.0, 3.0]))
    0.5
    """
    acc = acceleration_jacobian(jac, lam)
    with np.errstate(invalid="ignore"):
        out = isotropic_force(np.where(np.isfinite(acc), acc, np.inf), torque_limits=torque_limits,
                              torque_bias=torque_bias)
    return np.where(np.all(np.isfinite(np.asarray(lam, float)), axis=(-2, -1)), out, np.where(
        np.any(np.isnan(np.asarray(lam, float)), axis=(-2, -1)), np.nan, 0.0))


def acceleration_facets(normals: ArrayLike, lam: ArrayLike) -> FloatArray:
    """Facet normals of the acceleration set, ``nu^T Lambda`` (..., k, m), from the wrench set's ``nu`` (..., k, m).

    ``np.matmul``, not ``einsum``: the same m-term sums, a twentieth of the time on the
    Twin-Pantograph's (k, 30, 5) by (k, 5, 5) (einsum's generic loop, 0.30 s against 0.016 s on
    25,000 points).
    """
    with np.errstate(invalid="ignore"):         # an infinite mass times a zero entry: nan, as einsum gave
        return np.matmul(np.asarray(normals, float), np.asarray(lam, float))


def acceleration_ellipsoid(jac: ArrayLike, mass_matrix: ArrayLike, *, torque_limits: ArrayLike) -> Ellipsoid:
    """``{J M^-1 tau : |diag(1/t) tau| <= 1}``: radii (..., m), m/s^2, and axes (..., m, m) as columns.

    The image of the torque ball by ``J M^-1``: the left singular vectors and values of
    ``J M^-1 diag(t)`` (pycapacity ``acceleration_ellipsoid``).
    """
    jac, mass = np.asarray(jac, float), np.asarray(mass_matrix, float)
    t = actuator_limits("torque_limits", torque_limits, jac.shape[-1])
    image = np.swapaxes(np.linalg.solve(mass, np.swapaxes(jac, -1, -2)), -1, -2) * t     # J M^-1 diag(t)
    axes, radii = _left_svd(image)
    return Ellipsoid(radii=radii, axes=axes)


def acceleration_polytope_vertices(jac: ArrayLike, mass_matrix: ArrayLike, *, torque_max: ArrayLike,
                                   torque_min: ArrayLike | None = None) -> FloatArray:
    """Images ``J M^-1 tau`` of the torque box's corners (..., 2^n, m), m/s^2; the polytope is their hull.

    Corner ``k`` takes ``torque_max[u]`` where bit ``u`` of ``k`` is set, ``torque_min[u]`` (default
    ``-torque_max``) elsewhere.
    """
    jac, mass = np.asarray(jac, float), np.asarray(mass_matrix, float)
    n = jac.shape[-1]
    hi = np.asarray(torque_max, float)
    lo = -hi if torque_min is None else np.asarray(torque_min, float)
    bits = (np.arange(2**n)[:, None] >> np.arange(n)) & 1
    corners = np.where(bits == 1, hi, lo)                                        # (2^n, n)
    image = np.swapaxes(np.linalg.solve(mass, np.swapaxes(jac, -1, -2)), -1, -2)   # J M^-1
    return np.einsum("...mn,kn->...km", image, corners)


def peak_accelerations(force_along_axes: ArrayLike, lam: ArrayLike) -> FloatArray:
    """Paper 001 Table X's peak acceleration per axis: peak force over effective mass (..., m)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(force_along_axes, float) / effective_masses(lam)


def task_inertia(mech, q: ArrayLike, x: ArrayLike) -> FloatArray:
    """``mech.task_inertia(q, x)`` (..., m, m), compiled for the models that have a kernel for it.

    The Stewart and Inoue platforms' (registry kinds ``"stewart"``, ``"inoue"``, with a mass model)
    are ``kernels.stewart_mass`` and ``kernels.inoue_mass``, the 5-DOF Twin-Pantograph's with its
    task point on the pen's axis ``kernels.twin_mass``: the same formulas point by point, the
    same values to rounding; the model's numpy ``kinetic_form`` is their test reference and every
    other model's path. Like the
    wrench slices' kernels (``kernels.section``, ``kernels.wrench``) it is a piece of the numpy
    path, so ``kernels.use_compiled``, which chooses between the fused kernels and that path, does
    not turn it off.

    Parameters
    ----------
    mech : Mechanism
        With a mass model.
    q : array_like, shape (..., n)
    x : array_like, shape (..., m)
        A consistent pose; ``nan`` rows give ``nan``.

    Returns
    -------
    ndarray, shape (..., m, m)
        kg (length rows and columns), kg m^2 (angles), kg m (mixed).
    """
    from kinematics.registry import kind_of

    try:
        kind = kind_of(mech)
    except ValueError:              # a class that is not registered (a subclass): the model's own
        kind = None
    if kind == "twin_pantograph":
        from .kernels import twin_mass

        if twin_mass.supports(mech):
            return _twin_inertia(mech, np.asarray(x, float))
    if kind not in ("stewart", "inoue") or not mech.has_mass_model:
        return mech.task_inertia(q, x)
    return _platform_inertia(mech, kind, np.asarray(x, float))


def _twin_inertia(mech, x: FloatArray) -> FloatArray:
    """``Lambda`` (..., 5, 5) per twist of a 5-DOF Twin-Pantograph at poses ``x`` (..., 5), compiled."""
    from .kernels import twin_mass

    flat = np.ascontiguousarray(x.reshape(-1, 5))
    out = np.empty((len(flat), 5, 5))
    twin_mass.inertia_points(flat, *twin_mass.pack_mass(mech), out)
    return out.reshape(x.shape[:-1] + (5, 5))


def _platform_inertia(mech, kind: str, x: FloatArray) -> FloatArray:
    """``Lambda`` (..., 6, 6) per twist of a Stewart or Inoue platform at poses ``x`` (..., 6), compiled."""
    from kinematics.pose_memo import per_block
    from kinematics.rotations import batched_inverse, finite_rows, left_jacobian, rotation_matrix

    from .kernels import inoue_mass, stewart_mass

    batch = x.shape[:-1]
    flat = np.ascontiguousarray(x.reshape(-1, 6))
    placed, finite = finite_rows(flat, mech.home_pose())       # no warnings from a nan pose's rotation
    left = np.ascontiguousarray(per_block(left_jacobian, placed[:, 3:6]))
    out = np.empty((len(flat), 6, 6))
    if kind == "stewart":
        rot = np.ascontiguousarray(per_block(rotation_matrix, placed[:, 3:6]))
        stewart_mass.inertia_points(flat, rot, left, *stewart_mass.pack_mass(mech), out)
    else:
        cfg = mech.kinetic_configuration(flat)
        rot, *legs = (np.ascontiguousarray(cfg[name], dtype=np.float64)
                      for name in ("rot", "arm", "tips", "er", "n", "w", "distal", "tangent", "elbows"))
        inoue_mass.inertia_points(flat, np.ascontiguousarray(cfg["ok"] & finite), rot, left, *legs,
                                  *inoue_mass.pack_mass(mech), out)
    # Per rate of the rotation vector -> per twist, T^-T Lambda T^-1 (kinematics.dynamics.twist_columns),
    # only where an angle is not 0 (T = I there).
    turned = np.flatnonzero(finite & np.any(flat[:, 3:6] != 0, axis=-1))
    if len(turned):
        inv, _ = batched_inverse(mech.coordinate_rates_to_twist(flat[turned]))
        out[turned] = np.einsum("...ka,...kl,...lb->...ab", inv, out[turned], inv)
    return out.reshape(batch + (6, 6))
