"""The largest norm in a slice of a wrench set, its vertices and hull (``metrics.wrenches``).

The slice on rows ``R`` of ``W = {G s : |s_u| <= 1}`` (forces at zero moment, or moments at
zero force) is convex, so a norm's maximum over it is attained at a vertex.

The slice on rows ``R`` is the image under ``G_R`` of the section
``Q = {s in [-1, 1]^n : G_O s = 0}`` (``O`` the other ``r`` rows), and its vertices are images
of vertices of ``Q``: ``n - r`` coordinates at ``+-1`` (set ``B``) and ``r`` free (set ``F``)
solving ``G_O[:, F] s_F = -G_O[:, B] s_B`` (Cramer's rule, r <= 3), kept where
``|s_F| <= 1 + VERTEX_TOL``. That is ``C(n, r) 2^(n-r-1)`` small solves per pose (one of each
+-pair): 120 for the Twin-Pantograph's 5 x 6 force slice, 80 for a square 6 x 6. A kept
candidate ``s`` has ``s / (1 + VERTEX_TOL)`` in ``Q``, so the result overestimates by at most
the relative ``VERTEX_TOL``; a true vertex is missed only if its r x r solve loses more than
``-log10(VERTEX_TOL)`` digits (condition number above ~1e7).

A free set whose ``det G_O[:, F]`` is not above its own rounding-error bound
(``_det_rounding_bound``: ``K eps prod_u c_u``, ``c_u`` the column sums of ``|G_O[:, F]|``) is
skipped: its determinant may be 0 exactly (symmetric devices have identical or opposite
generators in ``G_O``, e.g. the Twin-Pantograph's two units on the slice ``(0, 2, 4)``), and a
solve with it divides noise by noise (once 22687 N for a true 2.05 N). Skipping loses no
vertex: a vertex of ``Q`` is a basic solution, ``n`` linearly independent active constraints,
the ``r`` rows of ``G_O`` (rank ``r``) and ``n - r`` of the bounds ``s_u = +-1``; the columns
not among those bounds form a free set with ``det G_O[:, F] != 0``, which reaches it. (A
vertex with more than ``n - r`` coordinates at +-1 has several free sets, some singular; a
vertex with exactly ``n - r`` has one, nonsingular.) A determinant within its bound but not 0
exactly (``|det| / prod c_u`` at most ``K eps``, about 1e-15) has no correct digit, nor have the
Cramer quotients formed with it, so the free set is treated as singular. It is singular for a
``G_O`` whose columns ``F`` move by at most ``2 sqrt(2) K eps`` relative to their sums ``c_u``
(r = 2: the smaller singular value of the column-scaled block is ``|det| / sigma_1`` with
``sigma_1 >= 1 / sqrt(2)``; r = 1 skips only exact zeros; r = 3 with two nearly dependent
directions: about ``sqrt(K eps)``): its vertices are lost only as far as such a change of ``G``
moves the slice (first order in it where ``G_O`` keeps rank ``r``).

Checked against linear programmes (scipy.optimize.linprog) in ``tests/metrics/test_wrenches.py``.
"""
from __future__ import annotations

import functools
import itertools
import math

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray

from . import linalg
from .linalg import as_jacobian

#: Relative slack with which a section-vertex candidate counts as inside the box (see module doc).
VERTEX_TOL = 1e-8


# -- slices: vertices and the largest norm ---------------------------------------------------


@functools.lru_cache(maxsize=32)
def _section_plan(n: int, r: int):
    """Index tables of the section's candidate vertices for ``n`` generators and ``r`` other rows.

    For each free set ``F`` (an ``r``-combination, ``itertools`` order, which is also the order
    of ``linalg.minors``' columns) and each fixed column ``j`` not in ``F``, Cramer's rule gives
    ``det(G_O[:, F]) x_j[k] = -det(G_O[:, F with column k replaced by G_O[:, j]])``, an
    ``r``-minor of ``G_O`` with the sign of sorting ``j`` into place, and the Schur complement
    ``det_F (G_R[i, j] + G_R[i, F] x_j)`` is the (r+1)-minor of rows ``(O, i)`` and columns
    ``(F, j)``, i.e. ``sigma_i sigma_j`` times the minor on sorted rows and columns
    (``sigma_j = (-1)^(r - position of j in sorted(F + j))``, ``sigma_i`` likewise for rows).
    Flipping every coefficient of one ``s_j`` only permutes the sign patterns (or swaps a
    +-pair), so ``sigma_j`` is moved onto the ``r`` Cramer coefficients and the (r+1)-minors
    are used unsigned; ``sigma_i`` flips coordinate ``i`` of every point (``_row_signs``).

    Returns ``(free (k, r), fixed (k, b), minor_index (b, k, r), minor_sign (b, k, r),
    wide_index (b, k))``, ``b = n - r``: ``wide_index`` into ``itertools.combinations(range(n), r + 1)``.
    """
    combos = list(itertools.combinations(range(n), r))
    where = {c: i for i, c in enumerate(combos)}
    wide = {c: i for i, c in enumerate(itertools.combinations(range(n), r + 1))}
    b = n - r
    free = np.array(combos, np.intp).reshape(len(combos), r)
    fixed = np.array([[u for u in range(n) if u not in c] for c in combos], np.intp).reshape(len(combos), b)
    index = np.zeros((b, len(combos), r), np.intp)
    sign = np.zeros((b, len(combos), r))
    wide_index = np.zeros((b, len(combos)), np.intp)
    for f, c in enumerate(combos):
        for jj, j in enumerate(fixed[f]):
            cols_wide = tuple(sorted(c + (int(j),)))
            wide_index[jj, f] = wide[cols_wide]
            sigma_j = -1.0 if (r - cols_wide.index(int(j))) % 2 else 1.0
            for k in range(r):
                cols = sorted(c[:k] + c[k + 1:] + (int(j),))
                moved = cols.index(int(j)) - k              # adjacent swaps taking j from slot k to its place
                index[jj, f, k] = where[tuple(cols)]
                sign[jj, f, k] = (-1.0 if moved % 2 == 0 else 1.0) * sigma_j
    return free, fixed, index, sign, wide_index


def _row_signs(m: int, rows) -> FloatArray:
    """``sigma_i`` (d,) of ``_section_plan``: the sign of sorting row ``i`` into the other rows."""
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    return np.array([-1.0 if (r - sorted(others + [i]).index(i)) % 2 else 1.0 for i in rows])


@functools.lru_cache(maxsize=32)
def _coefficient_index(n: int, r: int, d: int) -> np.ndarray:
    """Rows (k, b, r + d) of ``_section_candidates``' table ``[det; -det; wide]`` for each free set.

    ``[f, jj]`` lists the coefficients of ``s_j`` (``j = fixed[f, jj]``): the ``r`` Cramer
    coefficients ``sign * det[index]`` (a row of ``det`` or of ``-det``, the ``k`` rows after
    it) and the ``d`` Schur coefficients (rows of ``wide``, ``d`` blocks of ``C(n, r + 1)``).
    """
    free, fixed, index, sign, wide_index = _section_plan(n, r)
    k, b = len(free), n - r
    wide = math.comb(n, r + 1)
    rows = np.empty((k, b, r + d), np.intp)
    for f in range(k):
        for jj in range(b):
            rows[f, jj, :r] = index[jj, f] + np.where(sign[jj, f] > 0, 0, k)
            rows[f, jj, r:] = 2 * k + wide * np.arange(d) + wide_index[jj, f]
    return rows


def _det_rounding_bound(go: FloatArray, r: int) -> FloatArray:
    """Bound (k, ...) on the rounding error of ``linalg.minors``' ``det G_O[:, F]``, each free set ``F``.

    ``go`` holds the equilibrated rows ``G_O`` (r, n, ...) as ``_section_candidates`` computes
    them, ``F`` in ``itertools.combinations`` order. Derivation (``u = eps / 2``): each entry
    of ``go`` is ``g / beta`` rounded once (relative error <= u); the Laplace expansion of an
    r x r determinant along its first row, recursively, sums ``r!`` signed products of ``r``
    entries, and each product meets one rounding per multiplication and per addition on its
    way up (level ``k`` adds one multiplication and at most ``k - 1`` additions), i.e.
    ``sum_{k=2..r} k = r (r + 1) / 2 - 1`` roundings, plus the ``r`` of its entries. With
    ``K = r (r + 1) / 2 - 1 + r`` (1, 4, 8 for r = 1, 2, 3) the computed determinant differs
    from the exact one of ``G_O[:, F] / beta`` by at most ``gamma_K perm(|G_O[:, F]|)``
    (``gamma_K = K u / (1 - K u)``, Higham, Accuracy and Stability, section 3.1), and the
    permanent of a non-negative matrix is at most the product of its column sums,
    ``prod_{u in F} c_u`` with ``c_u = sum_i |go[i, u]|``. ``K eps prod c_u`` (twice ``K u``)
    exceeds ``gamma_K prod c_u`` with room for the rounding of the ``c_u`` and their product.
    Column sums, not a norm of the whole of ``G_O``: the ratio ``|det| / prod c_u`` does not
    change when a generator is scaled, so a small but exact column (a weak actuator) is no
    reason to skip. A determinant at or below the bound may be 0 in exact arithmetic; its
    sign and size are then noise. For r = 1 the determinant is the entry itself and the bound
    ``eps |entry|`` is never reached unless the entry is 0, as before.
    """
    free = _section_plan(go.shape[1], r)[0]
    c = np.sum(np.abs(go), axis=0)                                           # (n, ...)
    prod = c[free[:, 0]]
    for k in range(1, r):
        prod = prod * c[free[:, k]]
    return (r * (r + 1) // 2 - 1 + r) * np.finfo(float).eps * prod


def _section_candidates(a: FloatArray, rows):
    """Candidate vertices of the section ``Q = {s in [-1, 1]^n : G_O s = 0}``, imaged by ``G_R``.

    ``a`` holds finite ``G`` as entry arrays (m, n, N). Yields, for each free set ``F`` (an
    ``r``-combination of the generators) whose ``det G_O[:, F]`` is not 0 at every point,
    ``(w, det, inside)``: ``w`` (r + d, p, N) holds ``det_F s_F`` (the first ``r``) and
    ``det_F G_R s`` times ``_row_signs`` (the last ``d``) for each sign pattern ``s_B`` of the
    fixed set (one of each +-pair, in doubling order and up to a permutation); ``det`` (N,) is
    ``det G_O[:, F]``; ``inside`` (p, N) marks the candidates with
    ``|det_F s_F| <= (1 + VERTEX_TOL) |det_F|`` and ``|det_F|`` above its rounding-error bound
    (``_det_rounding_bound``), the vertices of ``Q``. At a point where ``|det_F|`` is within
    that bound the free set is treated as singular (no candidate): its solve would divide
    noise by noise, and every vertex of ``Q`` is reached by a nonsingular free set (module
    doc). A free set skipped at every point is not yielded. The arrays are reused from one
    free set to the next: copy what is kept.

    Every coefficient is a minor of ``G`` (``_section_plan``): the ``r``-minors of ``G_O`` and
    the (r+1)-minors of rows ``O`` plus one row of ``R``, computed once per block by
    ``linalg.minors`` (sharing their sub-minors) and shared by all free sets; a free set's
    ``b (r + d)`` coefficients are gathered in one indexing (``_coefficient_index``). ``G_O``
    rows are equilibrated first (the solution is unchanged).
    """
    m, n = a.shape[:2]
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r, d = len(others), len(rows)
    if not rows or r == 0 or r > 3 or r > n:
        raise ValueError(f"rows must leave 1 to 3 other rows of {m} (and at most n = {n}), got {rows}")
    # Equilibrate each row of G_O (an exact-solution-preserving scaling).
    g = np.array(a)
    go = g[others]
    row_big = np.max(np.abs(go), axis=1, keepdims=True)
    g[others] = go / np.where(row_big > 0, row_big, 1.0)
    det = linalg.minors(g, [tuple(others)])[0]                              # (k, N): det G_O[:, F] for every F
    b = n - r
    batch = det.shape[1:]
    p = 2 ** max(b - 1, 0)
    w = np.zeros((r + d, p) + batch)                                        # b = 0 (G_O square): only s = 0
    biggest, spare = np.empty((p,) + batch), np.empty((p,) + batch)
    inside = np.empty((p,) + batch, bool)
    with np.errstate(over="ignore", invalid="ignore"):
        # |det_F s_F| <= bound fails for every candidate where det_F is 0 to within its rounding
        # error (bound -1), nan included: such a free set's solve would divide noise by noise.
        bound = np.where(np.abs(det) > _det_rounding_bound(g[others], r), (1.0 + VERTEX_TOL) * np.abs(det), -1.0)
        if b > 0:
            wide = linalg.minors(g, [tuple(sorted(others + [i])) for i in rows])   # (d, C(n, r + 1), N)
            table = np.concatenate([det, -det, wide.reshape((-1,) + batch)])
            index = _coefficient_index(n, r, d)
    live = np.flatnonzero(np.any(bound >= 0, axis=tuple(range(1, det.ndim))))
    for f in live:
        with np.errstate(over="ignore", invalid="ignore"):
            if b > 0:
                z = table[index[f]]                                         # (b, r + d, N): coefficients of s_B
                # Sum over the sign patterns (s_B[0] = +1) by doubling: 2^b - 2 additions per
                # coefficient instead of b 2^(b-1) multiply-adds.
                w[:, 0] = z[0]
                h = 1
                for j in range(1, b):
                    np.subtract(w[:, :h], z[j][:, None], out=w[:, h:2 * h])
                    w[:, :h] += z[j][:, None]
                    h *= 2
            np.abs(w[0], out=biggest)
            for k in range(1, r):
                np.maximum(biggest, np.abs(w[k], out=spare), out=biggest)
            np.less_equal(biggest, bound[f], out=inside)
        yield w, det[f], inside


def slice_max_norm(generators: ArrayLike, *, rows) -> FloatArray:
    """Largest norm of ``w[rows]`` over ``w in W`` with ``w[others] = 0``, shape (...).

    Parameters
    ----------
    generators : array_like, shape (..., m, n)
        ``G = A diag(t)``, n >= m.
    rows : sequence of int
        The slice's coordinates (e.g. the force rows); 1 to 3 other rows.

    Returns
    -------
    ndarray, shape (...)
        In the unit of ``G``'s rows ``rows``. ``nan`` where ``G`` is not finite or no
        candidate vertex exists (``G_O`` of rank below ``r``).

    Notes
    -----
    Compiled point by point (``kernels.section``), with the operations of ``_section_candidates``
    in its order: the same bits as those numpy passes, kept as the tests' reference.

    Examples
    --------
    >>> round(float(slice_max_norm(np.diag([2.0, 3.0, 4.0]), rows=[0, 1])) ** 2, 12)   # |(2, 3)|^2
    13.0
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    batch = g.shape[:-2]
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    if not rows or r == 0 or r > 3 or r > n:
        raise ValueError(f"rows must leave 1 to 3 other rows of {m} (and at most n = {n}), got {rows}")
    # C-contiguous and writeable (numba builds another version for a read-only array): no copy
    # where the generators are so already (the kernel only reads them).
    flat = np.require(g.reshape((-1, m, n)), dtype=np.float64, requirements=("C", "W"))
    out = np.empty(len(flat))
    if len(flat):
        from .kernels import section

        tables, size, k_eps = _section_kernel_plan(m, n, tuple(rows))
        section.section_max_norm(flat, *tables, k_eps, 1.0 + VERTEX_TOL, out, np.empty(size))
    return out.reshape(batch)


@functools.lru_cache(maxsize=32)
def _section_kernel_plan(m: int, n: int, rows: tuple[int, ...]):
    """``kernels.section.section_max_norm``'s tables for ``n`` generators, ``m`` rows and the slice ``rows``."""
    from .kernels import section

    others = tuple(i for i in range(m) if i not in rows)
    r, d = len(others), len(rows)
    levels_a, out_a = linalg._minor_plan(n, (others,))
    packed_a, free = section.pack_levels(levels_a), _section_plan(n, r)[0]
    if n > r:
        levels_b, out_b = linalg._minor_plan(n, tuple(tuple(sorted(others + (i,))) for i in rows))
        packed_b, index = section.pack_levels(levels_b), _coefficient_index(n, r, d)
    else:                   # G_O square (b = 0): the only candidate is s = 0, no wide minor
        packed_b, out_b = np.full((1, 1, 3), -1, np.int64), np.zeros((d, 1), np.intp)
        index = np.zeros((len(free), 0, r + d), np.intp)
    tables = (np.array(others, np.int64), np.array(rows, np.int64), packed_a, packed_b,
              np.ascontiguousarray(out_a, np.int64), np.ascontiguousarray(out_b, np.int64),
              np.ascontiguousarray(free, np.int64), np.ascontiguousarray(index, np.int64))
    size = section.scratch_size(packed_a, packed_b, out_b, len(free), d, n)
    k_eps = (r * (r + 1) // 2 - 1 + r) * np.finfo(float).eps         # _det_rounding_bound's K eps
    return tables, size, float(k_eps)


def slice_vertices(generators: ArrayLike, *, rows) -> FloatArray:
    """Vertices (k, d) of the slice on ``rows`` of one wrench set, ``G`` (m, n).

    The convex hull's vertices among the images of Q's vertices (duplicates removed, both
    members of each +-pair listed). Empty (0, d) where ``G`` is not finite.

    Parameters
    ----------
    generators : array_like, shape (m, n)
        ``G = A diag(t)`` of one pose (no batch axes), ``n >= m``.
    rows : sequence of int
        The slice's task rows (``d`` of them), leaving 1 to 3 other rows.

    Returns
    -------
    ndarray, shape (k, d)
        In the unit of the rows ``rows``.

    Raises
    ------
    ValueError
        If ``generators`` has batch axes.

    Examples
    --------
    >>> slice_vertices(np.diag([2.0, 3.0, 4.0]), rows=[0, 1]).shape
    (4, 2)
    """
    g = as_jacobian(generators, "generators")
    if g.ndim != 2:
        raise ValueError(f"generators must be one (m, n) matrix, got {g.shape}")
    d = len(list(rows))
    if not np.all(np.isfinite(g)):
        return np.zeros((0, d))
    # The slice of G Q is linear in G: work on G / s with s a power of two near its largest entry
    # (exact, so the answer at torques scaled by 2^k is the same bits times 2^k), and scale back.
    # Products of r + d generators (determinants, squared norms) then neither overflow at 1e300
    # N m nor underflow at 1e-300 N m, and the hull's tolerances are relative.
    scale = power_of_two_scale(g)
    pts = _slice_vertices_unit(g / scale, list(rows), d)
    with np.errstate(over="ignore"):        # a vertex past the float range is inf in truth too
        return pts * scale


def power_of_two_scale(values: ArrayLike) -> float:
    """The power of two nearest above ``max |values|`` (1 for an all-zero or non-finite array).

    Dividing by it is exact, and leaves the largest entry in [0.5, 1).

    Parameters
    ----------
    values : array_like
        Any finite numbers.

    Returns
    -------
    float

    Examples
    --------
    >>> power_of_two_scale([3.0, -0.1]), power_of_two_scale([0.0])
    (4.0, 1.0)
    """
    biggest = float(np.max(np.abs(values), initial=0.0))
    if biggest == 0.0 or not np.isfinite(biggest):
        return 1.0
    return float(np.ldexp(1.0, np.frexp(biggest)[1]))


def _slice_vertices_unit(g: FloatArray, rows: list[int], d: int) -> FloatArray:
    """``slice_vertices`` of generators whose largest entry is in [0.5, 1)."""
    r = g.shape[0] - d
    signs = _row_signs(g.shape[0], list(rows))
    found = []
    for w, det, inside in _section_candidates(linalg.components(g[None]), rows):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            found.append((w[r:, :, 0] / det[0]).T[inside[:, 0]] * signs)      # (kept, d)
    pts = np.concatenate(found)
    pts = np.concatenate([pts, -pts])
    if len(pts) == 0:
        return pts
    tol = 1e-9 * float(np.max(np.linalg.norm(pts, axis=1)))
    # Sorted on coordinates snapped to the tolerance: rounding noise (a 0 that comes out as
    # -7e-15 at one torque scale and 0 at another) does not reorder the vertices.
    key = np.round(pts / tol) if tol > 0 else pts
    pts = _dedupe(pts[np.lexsort(key.T[::-1])], tol)
    # With redundant actuation some images of Q's vertices lie inside the slice: keep the hull's.
    from scipy.spatial import ConvexHull, QhullError
    if d >= 2 and len(pts) > d:
        try:
            pts = pts[np.sort(ConvexHull(pts).vertices)]
        except QhullError:          # flat slice (a singular pose): keep every candidate
            pass
    return pts


def _dedupe(points: FloatArray, tol: float) -> FloatArray:
    """``points`` without near-duplicates (max-norm distance <= ``tol``), first of each kept."""
    out: list[np.ndarray] = []
    for p in points:
        if not out or np.min(np.max(np.abs(np.array(out) - p), axis=1)) > tol:
            out.append(p)
    return np.array(out).reshape(-1, points.shape[-1])


def hull_faces(vertices: ArrayLike) -> list[tuple[int, ...]]:
    """Faces of the convex hull of ``vertices`` (k, 3) as vertex-index cycles (coplanar triangles merged).

    ``[]`` when the points span less than 3 dimensions. 2D points (k, 2) give one polygon.

    Parameters
    ----------
    vertices : array_like, shape (k, 3) or (k, 2)
        Points, e.g. ``slice_vertices``.

    Returns
    -------
    list of tuple of int
        Indices into ``vertices``, one cycle per face.

    Examples
    --------
    >>> cube = np.array([[x, y, z] for x in (1, -1) for y in (1, -1) for z in (1, -1)], float)
    >>> len(hull_faces(cube))
    6
    """
    from scipy.spatial import ConvexHull, QhullError
    v = np.asarray(vertices, float)
    if len(v) < v.shape[-1] + 1 or not np.all(np.isfinite(v)):
        return []
    # Faces are a property of the shape, not of its size: a power-of-two scaling (exact) makes
    # the hull, the coplanarity tolerances and the winding the same at 1e-300 N as at 1 N.
    v = v / power_of_two_scale(v)
    try:
        hull = ConvexHull(v)
    except QhullError:
        return []
    if v.shape[-1] == 2:
        return [tuple(int(i) for i in hull.vertices)]
    size = float(np.max(np.linalg.norm(v, axis=1)))
    groups: list[tuple[np.ndarray, set[int]]] = []
    for eq, simplex in zip(hull.equations, hull.simplices):
        for normal, members in groups:
            if np.dot(normal[:3], eq[:3]) > 1 - 1e-9 and abs(normal[3] - eq[3]) <= 1e-9 * size:
                members.update(int(i) for i in simplex)
                break
        else:
            groups.append((eq, {int(i) for i in simplex}))
    faces = []
    for eq, members in groups:
        idx = np.array(sorted(members))
        pts = v[idx]
        centre = pts.mean(axis=0)
        normal = eq[:3]
        # In-plane axis from the member farthest from the centre: never a zero vector.
        spokes = (pts - centre) - np.outer((pts - centre) @ normal, normal)
        e1 = spokes[np.argmax(np.linalg.norm(spokes, axis=1))]
        e1 = e1 / np.linalg.norm(e1)
        e2 = np.cross(normal, e1)
        angle = np.arctan2((pts - centre) @ e2, (pts - centre) @ e1)
        cycle = [int(i) for i in idx[np.argsort(angle)]]
        start = cycle.index(min(cycle))      # not where the angle wraps, which rounding decides
        faces.append(tuple(cycle[start:] + cycle[:start]))
    return sorted(faces)            # not in qhull's facet order, which rounding decides
