"""The largest norm in a slice of a redundant model's gravity-biased wrench set, from the section's vertices.

With a torque bias ``b`` (gravity) the wrench set of ``G = A diag(t)`` (m x n, n > m) is the zonotope
``Z = {c + G s : s in [-1, 1]^n}`` with ``c = -G beta``, ``beta = b / t`` (``quantity_nodes.slab_shifts``
builds ``c`` so). Its slice on rows ``R`` (``d`` of them; the other ``r = m - d`` rows ``O`` at 0) is
the image ``f = G_R (s - beta)`` of ``P = {s in [-1, 1]^n : G_O (s - beta) = 0}``: ``beta`` itself,
not ``c``, so the constraint's right side is exactly 0 and no rounding of ``c`` enters. ``|f|`` is
convex, so its maximum over ``P`` is at a vertex, and every vertex of ``P`` is a basic solution:
``n - r`` coordinates at ``+-1`` and the ``r`` others, a free set ``F`` with ``det G_O[:, F] != 0``,
solving ``G_O[:, F] (s_F - beta_F) = -G_O[:, B] (s_B - beta_B)`` (``wrench_slices``' module doc: a
vertex with more coordinates at the bounds is reached by a nonsingular free set too, where
``G_O`` has rank ``r``). The candidates are the unbiased section's (``wrench_slices``) with the box
moved by ``-beta``: the same minors of ``G``, all ``2^(n - r)`` sign patterns (no +-pairs), and a
constant per free set (``kernels.biased_section``). For the Twin-Pantograph's force slice that
is 15 x 16 candidates a point against the slab enumeration's 455 x 8 solves
(``wrench_facets.slab_slice_vertex_max_norm``): its 120 x 120 default map of the anisotropic
force under upright gravity, one thread, 0.18-0.19 s CPU against 1.48-1.56 s (0.08-0.09 s with
gravity off).

What is decided, and what is handed back
----------------------------------------
Every computed minor has a rounding bound (``wrench_slices._det_rounding_bound``: ``K eps`` times
the product of its columns' sums of ``|G_O|``), and every candidate's Cramer value
``det s_F[c]`` one from those and its own sums (``kernels.biased_section._offsets``), ``E_c``. So:

* A candidate is kept where ``|det s_F[c]| <= |det| + bnd_det + E_c`` for every ``c``: a vertex
  reached by a free set above its rounding bound is never dropped by rounding.
* A kept candidate is exactly a vertex of the section whose free coordinates may exceed the box
  by ``x = max_c (|det s_F[c]| + E_c) / (|det| - bnd_det) - 1``; where ``x <= VERTEX_TOL`` its image
  is a point of the slice of the same set with every rating multiplied by ``1 + VERTEX_TOL`` and the
  same gravity torque (``s / (1 + x)`` is in the box, ``G (1 + x)`` and ``beta / (1 + x)`` give the
  same ``f``). The answer is then between the true maximum at the ratings ``t`` and at
  ``(1 + VERTEX_TOL) t``, up to the rounding of the winning candidate's image. (In the slice's
  own terms: a rounding slack ``x`` on ``|s_F| <= 1`` moves that image by at most
  ``x sum_{u in F} |G_R[:, u]|`` against the clamped ``s``, but the clamped ``s`` is in general off
  the constraint, hence the statement on the ratings.)
* A free set whose ``det`` is not above its rounding bound is singular to within rounding and
  gives no candidate, as in the unbiased section (``wrench_slices``' module doc: the answer is
  then that of a ``G_O`` whose columns ``F`` move by about ``K eps`` of their sums). Handing such
  points back instead would hand back every point of a symmetric device: the Twin-Pantograph's
  two units are mirror images, so ``G_O`` has three pairs of identical or opposite columns (its
  force slice: ``det`` exactly 0, or 3e-17 against a bound of 8e-16, at every pose), and the
  slab path drops the matching dependent slab triples (``64 eps``) the same way.
* The point is handed back (``decided`` False, for the slab path) where the rest cannot be
  said: a non-finite entry of ``G`` or ``beta``; no free set above its bound (``G_O`` of rank
  below ``r`` within rounding); no kept candidate (an empty slice, or one lost to rounding); a
  non-finite image; or a maximum reached only by candidates beyond ``VERTEX_TOL`` of the box.

Checked against the slab path and an exact rational enumeration in
``tests/metrics/test_biased_sections.py``.
"""
from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from .linalg import as_jacobian
from .wrench_slices import VERTEX_TOL, _section_kernel_plan, _section_plan


def biased_slice_max_norm(generators: ArrayLike, bias: ArrayLike, *, rows) -> tuple[FloatArray, np.ndarray]:
    """Largest norm of the slice on ``rows`` of ``{G (s - beta) : |s| <= 1}``, and where it is decided.

    Parameters
    ----------
    generators : array_like, shape (..., m, n), n > m
        ``G = A diag(t)``: each actuator's wrench at full rated torque.
    bias : array_like, shape (..., n)
        ``beta = b / t``: the torque bias per unit of the rating.
    rows : sequence of int
        The slice's rows (``wrenches.force_rows`` or ``moment_rows``), leaving 1 to 3 other rows.

    Returns
    -------
    values : ndarray, shape (...)
        In the unit of ``G``'s rows ``rows``; ``nan`` where not decided.
    decided : ndarray of bool, shape (...)
        Where ``values`` is the answer (module doc); elsewhere ask the slab path.

    Examples
    --------
    >>> g = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    >>> value, ok = biased_slice_max_norm(g, [0.5, 0.0, 0.0], rows=[0])
    >>> float(value), bool(ok)       # s - beta = (-1.5, 1, -1): row 0 is -2.5, row 1 is 0
    (2.5, True)
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    if not rows or not 1 <= len(others) <= 3 or n <= len(others):
        raise ValueError(f"rows must leave 1 to 3 other rows of {m} (and fewer than n = {n}), got {rows}")
    beta = np.asarray(bias, float)
    batch = np.broadcast_shapes(g.shape[:-2], beta.shape[:-1])
    flat = np.array(np.broadcast_to(g, batch + (m, n)).reshape((-1, m, n)), np.float64, order="C")
    beta = np.ascontiguousarray(np.broadcast_to(beta, batch + (n,)).reshape((-1, n)), np.float64)
    out = np.empty(len(flat))
    decided = np.zeros(len(flat), bool)
    if len(flat):
        from .kernels import biased_section

        tables, _, k_eps = _section_kernel_plan(m, n, tuple(rows))
        fixed, signs = _fixed_signs(n, len(others))
        others_t, rows_t, packed_a, packed_b, out_a, out_b, free, index = tables
        size = biased_section.biased_scratch_size(packed_a, packed_b, out_b, len(free), len(rows), n)
        biased_section.biased_section_max_norm(flat, beta, *tables, fixed, signs, k_eps, VERTEX_TOL, out, decided,
                                               np.empty(size))
    return out.reshape(batch), decided.reshape(batch)


@functools.lru_cache(maxsize=32)
def _fixed_signs(n: int, r: int) -> tuple[np.ndarray, np.ndarray]:
    """Each free set's fixed columns (k, b) and their ``sigma_j`` (k, b), ``_section_plan``'s order.

    ``sigma_j = (-1)^(r - position of j in sorted(F + j))``: ``_section_plan`` multiplied every
    coefficient of ``s_j`` by it (a relabelling of the sign patterns, for a box symmetric about 0);
    the biased offsets ``beta_j`` need it undone.
    """
    free, fixed = _section_plan(n, r)[:2]
    signs = np.empty(fixed.shape)
    for f in range(len(free)):
        for jj, j in enumerate(fixed[f]):
            position = sorted([int(u) for u in free[f]] + [int(j)]).index(int(j))
            signs[f, jj] = -1.0 if (r - position) % 2 else 1.0
    return np.ascontiguousarray(fixed, np.int64), signs
