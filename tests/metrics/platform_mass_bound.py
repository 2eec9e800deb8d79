"""What the Stewart and Inoue kinetic-form tests share: their sample points and the rounding bound's frame.

Each test module's docstring derives its own chain and amplification ``k``; the sum over the
terms ``T = sum_t w_t |F_t|^2`` and the turned poses' ``|T^-1|^2`` step are common to both
(``test_kernel_mass_stewart.py`` explains them).
"""
from __future__ import annotations

import numpy as np

from kinematics.bodies import body_arrays
from kinematics.rotations import batched_inverse

EPS = np.finfo(float).eps
#: Roundings along a column's longest chain (each module's docstring).
CHAIN = 60
POINTS = 300
SEED = 20261207


def feasible_points(mech, grid, count: int = POINTS, seed: int = SEED):
    """A fixed random subset of the grid's feasible points: ``x`` (k, 6), ``q`` (k, n)."""
    pts = grid.points(mech.task_names).reshape(-1, 6)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    at = np.sort(np.random.default_rng(seed).choice(np.flatnonzero(ok), count, replace=False))
    return pts[at], q[at]


def entry_bound(mech, q: np.ndarray, x: np.ndarray, k: np.ndarray, terms: int) -> np.ndarray:
    """The two paths' largest entry difference per point, shape (k,).

    Parameters
    ----------
    mech : StewartPlatform or InouePlatform
    q, x : ndarray, shape (k, n) and (k, 6)
    k : ndarray, shape (k,)
        The chain's amplification at each point (the module's docstring).
    terms : int
        The constant of the module's bound: ``(2 N k^2 + terms) eps T``.

    Returns
    -------
    ndarray, shape (k,)
    """
    masses, _, tensors = body_arrays(mech.bodies())
    jv, jw, _, g = mech.body_velocities(q, x)
    total = np.einsum("u,uan->n", mech.reflected_rotor_inertias(), g ** 2)
    for b, mass in enumerate(masses):
        total += mass * np.sum(jv[b] ** 2, axis=(0, 1))
        total += np.linalg.norm(tensors[b], 2) * np.sum(jw[b] ** 2, axis=(0, 1))
    bound = (2 * CHAIN * k ** 2 + terms) * EPS * total
    turned = np.any(x[:, 3:] != 0, axis=-1)
    if np.any(turned):
        inv, _ = batched_inverse(mech.coordinate_rates_to_twist(x[turned]))
        size = np.linalg.norm(inv, 2, axis=(-2, -1)) ** 2
        bound[turned] = bound[turned] * size + 12 * EPS * size * total[turned]
    return bound
