"""The implementations of ``metrics.wrenches`` (and friends) before the speed-ups of issue 11, kept
verbatim as references for ``test_fast_kernels.py``: the optimized kernels must give these
numbers to a derived tolerance (or bit for bit, where they do the same operations in the same
order). Not collected by pytest (no ``test_`` prefix); docstrings trimmed to one line where they
were long. At the end, the first speed-up's ``linalg.minors`` (gathered) and ``slice_max_norm``
(shared minors), the references of the second.
"""
from __future__ import annotations

import functools
import itertools

import numpy as np
from numpy.typing import ArrayLike

from kinematics.arrays import FloatArray
from metrics import linalg
from metrics.linalg import as_jacobian
from metrics.torque_box import sign_patterns

VERTEX_TOL = 1e-8


def _minor_table(a: FloatArray):
    """A memoised ``minor(rows, cols)`` of entry arrays ``a`` (m, n, N), by Laplace expansion."""
    memo: dict[tuple, FloatArray] = {}

    def minor(rows: tuple[int, ...], cols: tuple[int, ...]) -> FloatArray:
        if len(rows) == 1:
            return a[rows[0], cols[0]]
        key = (rows, cols)
        if key not in memo:
            r0, rest = rows[0], rows[1:]
            acc = a[r0, cols[0]] * minor(rest, cols[1:])
            for j in range(1, len(cols)):
                term = a[r0, cols[j]] * minor(rest, cols[:j] + cols[j + 1:])
                acc = acc - term if j % 2 else acc + term
            memo[key] = acc
        return memo[key]

    return minor


def facets(generators: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Slabs ``|nu_k . w| <= h_k`` whose intersection is ``W = {G s : |s| <= 1}``.

    Parameters
    ----------
    generators : array_like, shape (..., m, n), n >= m
        ``G = A diag(t)``: each actuator's wrench at full torque.

    Returns
    -------
    normals : ndarray, shape (..., k, m)
        ``nu_S`` for each of the ``k = C(n, m-1)`` subsets ``S`` (``itertools.combinations``
        order), from columns scaled to unit length; not normalised (only ratios matter).
    offsets : ndarray, shape (..., k)
        ``h_S = sum_u |nu_S . g_u|``. ``nan`` (both) where ``G`` has a non-finite entry.
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    if n < m:
        raise ValueError(f"generators needs at least as many columns as rows (..., {m}, >= {m}), got {g.shape}")
    batch = g.shape[:-2]
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    # Unit columns: minors stay within [-1, 1] whatever the scale of G (1e-300 ... 1e300).
    big = np.max(np.abs(flat), axis=-2)
    length = big * np.sqrt(np.sum((flat / np.where(big > 0, big, 1.0)[:, None, :]) ** 2, axis=-2))   # (N, n)
    unit = flat / np.where(length > 0, length, 1.0)[:, None, :]
    a = np.ascontiguousarray(np.moveaxis(unit, 0, -1))                      # (m, n, N)
    minor = _minor_table(a)
    subsets = list(itertools.combinations(range(n), m - 1))
    normals = np.empty((len(subsets), m) + a.shape[2:])
    for k, subset in enumerate(subsets):
        for i in range(m):
            rows = tuple(r for r in range(m) if r != i)
            value = minor(rows, subset) if m > 1 else np.ones(a.shape[2:])
            normals[k, i] = -value if i % 2 else value
    dots = np.einsum("kiN,iuN->kuN", normals, a)
    offsets = np.einsum("kuN,uN->kN", np.abs(dots), np.moveaxis(length, 0, -1))
    normals = np.moveaxis(normals, -1, 0)
    offsets = np.moveaxis(offsets, -1, 0)
    normals[~finite] = np.nan
    offsets[~finite] = np.nan
    return normals.reshape(batch + normals.shape[1:]), offsets.reshape(batch + offsets.shape[1:])



def slice_inscribed_radius(normals: ArrayLike, offsets: ArrayLike, *, rows) -> FloatArray:
    """Radius of the largest ball about 0 in the slice of ``W`` on ``rows``, shape (...).

    ``min_k h_k / |nu_k[rows]|`` over the slabs of ``facets``; ``nan`` where every normal is
    zero (``G`` of rank below m - 1: no slab description) or ``G`` is not finite.

    Parameters
    ----------
    normals : array_like, shape (..., k, m)
        Slab normals ``nu_k`` (``facets``).
    offsets : array_like, shape (..., k)
        Slab offsets ``h_k``.
    rows : sequence of int
        The slice's task rows.

    Returns
    -------
    ndarray, shape (...)
        In the unit of the wrench rows ``rows`` (N or N m).

    Examples
    --------
    >>> nu, h = facets(np.diag([2.0, 3.0, 4.0]))
    >>> round(float(slice_inscribed_radius(nu, h, rows=[0, 1])), 12)
    2.0
    """
    nu = np.asarray(normals, float)
    h = np.asarray(offsets, float)
    part = nu[..., list(rows)]
    with np.errstate(invalid="ignore"):
        big = np.max(np.abs(part), axis=-1)
        safe = np.where((big > 0) & np.isfinite(big), big, 1.0)
        den = big * np.sqrt(np.sum((part / safe[..., None]) ** 2, axis=-1))
    # An infinite normal (square J at a direct singularity) bounds that direction at 0, as in
    # ``isotropy.facet_distances``; a zero one bounds nothing; nan stays nan.
    den = np.where(np.isinf(big), np.inf, den)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(den == 0, np.inf, h / den)
    radius = np.min(ratio, axis=-1)
    degenerate = ~np.any(np.abs(nu) > 0, axis=(-2, -1))
    return np.where(degenerate, np.nan, radius)



def _adjugate(m: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Adjugate (r, r, ...) and determinant (...) of entry arrays ``m`` (r, r, ...), r <= 3."""
    r = m.shape[0]
    if r == 1:
        return np.ones_like(m), m[0, 0]
    if r == 2:
        adj = np.stack([np.stack([m[1, 1], -m[0, 1]]), np.stack([-m[1, 0], m[0, 0]])])
        return adj, m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    c = np.empty_like(m)
    for i in range(3):
        for j in range(3):
            i1, i2 = [k for k in range(3) if k != i]
            j1, j2 = [k for k in range(3) if k != j]
            c[i, j] = m[i1, j1] * m[i2, j2] - m[i1, j2] * m[i2, j1]
            if (i + j) % 2:
                c[i, j] = -c[i, j]
    det = m[0, 0] * c[0, 0] + m[0, 1] * c[0, 1] + m[0, 2] * c[0, 2]
    return np.swapaxes(c, 0, 1), det


def _section_candidates(generators: ArrayLike, rows):
    """Yield ``(points (p, d, N), inside (p, N))``: images ``G_R s`` of candidate vertices of Q.

    ``generators`` (N, m, n) finite; one block per free set ``F``; ``p = 2^(n-r-1)`` sign
    patterns (one of each +-pair). ``G_O`` rows are equilibrated (the solution is unchanged).
    """
    g = np.asarray(generators, float)
    m, n = g.shape[-2:]
    rows = list(rows)
    others = [i for i in range(m) if i not in rows]
    r = len(others)
    if not rows or r == 0 or r > 3 or r > n:
        raise ValueError(f"rows must leave 1 to 3 other rows of {m} (and at most n = {n}), got {rows}")
    a = np.ascontiguousarray(np.moveaxis(g, 0, -1))                      # (m, n, N)
    go = a[others]
    scale = np.max(np.abs(go), axis=(0, 1))
    go = go / np.where(scale > 0, scale, 1.0)
    # Equilibrate each row of G_O (an exact-solution-preserving scaling).
    row_big = np.max(np.abs(go), axis=1, keepdims=True)
    go = go / np.where(row_big > 0, row_big, 1.0)
    gr = a[rows]
    signs = sign_patterns(n - r, half=True) if n > r else np.ones((1, 0))
    for free in itertools.combinations(range(n), r):
        fixed = [u for u in range(n) if u not in free]
        adj, det = _adjugate(go[:, list(free)])
        c = go[:, fixed]                                                    # (r, b, N)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x = -np.einsum("ijN,jbN->ibN", adj, c) / det                     # s_F = x s_B
            s_free = np.einsum("pb,ibN->piN", signs, x)                      # (p, r, N)
            inside = np.all(np.abs(s_free) <= 1.0 + VERTEX_TOL, axis=1) & (det != 0)
            h = np.einsum("dfN,fbN->dbN", gr[:, list(free)], x) + gr[:, fixed]
            points = np.einsum("pb,dbN->pdN", signs, h)
        yield points, inside


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
    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    batch = g.shape[:-2]
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    part = flat[:, list(rows), :]
    size = np.max(np.abs(part), axis=(-2, -1))
    size = np.where(size > 0, size, 1.0)
    scaled = flat.copy()
    scaled[:, list(rows), :] = part / size[:, None, None]      # |G_R s| computed near 1: no under/overflow
    best = np.full(flat.shape[0], -1.0)
    for points, inside in _section_candidates(scaled, rows):
        norm2 = np.sum(points * points, axis=1)                  # (p, N)
        best = np.maximum(best, np.max(np.where(inside, norm2, -1.0), axis=0))
    out = np.where(finite & (best >= 0), size * np.sqrt(np.maximum(best, 0.0)), np.nan)
    return out.reshape(batch)


# -- slice_max_norm of commits bd6f61a and 1a50ed3 ---------------------------------------------------
# Shared minors and Schur coefficients, a Python loop over every free set; the kernel after it does
# the same operations in the same order on the free sets it does not skip, so the same numbers.
SECTION_BLOCK = 4096


@functools.lru_cache(maxsize=64)
def _minor_plan(n_cols: int, row_sets: tuple[tuple[int, ...], ...]):
    """Index tables to evaluate every column-combination minor of ``row_sets`` level by level.

    Level ``k`` holds the minors of size ``k`` needed: a row set (a suffix, by Laplace
    expansion along its first row, of a requested set) with each ``k``-combination of the
    ``n_cols`` columns. Returns ``(levels, out)``: per level ``(entry, sub, sign)`` arrays of
    shape (E_k, k) (``entry`` a flat ``row * n_cols + col`` index, ``sub`` the index of the
    complementary minor in the level below, ``sign`` +-1), and ``out`` (len(row_sets), C(n, s))
    indices into the top level.
    """
    size = len(row_sets[0])
    needed: list[dict] = [dict() for _ in range(size + 1)]          # level -> {(rows, cols): index}
    for rows in row_sets:
        for t in range(size):
            suffix = rows[t:]
            for cols in itertools.combinations(range(n_cols), size - t):
                needed[size - t].setdefault((suffix, cols), len(needed[size - t]))
    levels = []
    for k in range(1, size + 1):
        keys = sorted(needed[k], key=needed[k].get)
        entry = np.empty((len(keys), k), np.intp)
        sub = np.zeros((len(keys), k), np.intp)
        for e, (rows, cols) in enumerate(keys):
            for p, col in enumerate(cols):
                entry[e, p] = rows[0] * n_cols + col
                if k > 1:
                    sub[e, p] = needed[k - 1][(rows[1:], cols[:p] + cols[p + 1:])]
        sign = np.where(np.arange(k) % 2 == 0, 1.0, -1.0)
        levels.append((entry, sub, sign))
    combos = list(itertools.combinations(range(n_cols), size))
    out = np.array([[needed[size][(rows, cols)] for cols in combos] for rows in row_sets], np.intp)
    return levels, out


def minors(a: ArrayLike, row_sets) -> FloatArray:
    """Every ``s x s`` minor of entry arrays ``a`` (m, n, ...) on the given row sets (one gather per level and term)."""
    a = np.asarray(a, dtype=np.float64)
    m, n = a.shape[:2]
    row_sets = tuple(tuple(int(r) for r in rows) for rows in row_sets)
    size = len(row_sets[0])
    if any(len(rows) != size or list(rows) != sorted(set(rows)) or rows[0] < 0 or rows[-1] >= m for rows in row_sets):
        raise ValueError(f"row_sets must be sorted, distinct rows of {m}, all of one size, got {row_sets}")
    if not 1 <= size <= n:
        raise ValueError(f"row_sets' size must be between 1 and n = {n}, got {size}")
    levels, out = _minor_plan(n, row_sets)
    flat = a.reshape((m * n,) + a.shape[2:])
    prev = None
    for k, (entry, sub, sign) in enumerate(levels, start=1):
        if k == 1:
            prev = flat[entry[:, 0]]
            continue
        acc = flat[entry[:, 0]] * prev[sub[:, 0]]
        for p in range(1, k):
            term = flat[entry[:, p]] * prev[sub[:, p]]
            acc = acc - term if sign[p] < 0 else acc + term
        prev = acc
    return prev[out]


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


def section_candidates_minors(a: FloatArray, rows):
    """Candidate vertices of the section ``Q = {s in [-1, 1]^n : G_O s = 0}``, imaged by ``G_R``.

    ``a`` holds finite ``G`` as entry arrays (m, n, N). Yields, for each free set ``F`` (an
    ``r``-combination of the generators), ``(w, det, inside)``: ``w`` (r + d, p, N) holds
    ``det_F s_F`` (the first ``r``) and ``det_F G_R s`` times ``_row_signs`` (the last ``d``) for
    each sign pattern ``s_B`` of the fixed set (one of each +-pair, in doubling order and up to
    a permutation); ``det`` (N,) is ``det G_O[:, F]``; ``inside`` (p, N) marks the candidates
    with ``|det_F s_F| <= (1 + VERTEX_TOL) |det_F|`` and ``det_F != 0``, the vertices of ``Q``.
    The arrays are reused from one free set to the next: copy what is kept.

    Every coefficient is a minor of ``G`` (``_section_plan``): the ``r``-minors of ``G_O`` and
    the (r+1)-minors of rows ``O`` plus one row of ``R``, computed once per block by
    ``linalg.minors`` (sharing their sub-minors) and shared by all free sets. ``G_O`` rows are
    equilibrated first (the solution is unchanged).
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
    free, fixed, index, sign, wide_index = _section_plan(n, r)
    det = minors(g, [tuple(others)])[0]                              # (k, N): det G_O[:, F] for every F
    b = n - r
    batch = det.shape[1:]
    w = np.zeros((r + d, 2 ** max(b - 1, 0)) + batch)                      # b = 0 (G_O square): only s = 0
    if b > 0:
        with np.errstate(over="ignore", invalid="ignore"):
            wide = minors(g, [tuple(sorted(others + [i])) for i in rows])   # (d, C(n, r + 1), N)
        z = np.empty((b, r + d) + batch)                                    # coefficients of s_B
    for f in range(len(free)):
        det_f = det[f]
        if b > 0:
            with np.errstate(over="ignore", invalid="ignore"):
                z[:, :r] = sign[:, f, :, None] * det[index[:, f]]
                z[:, r:] = np.moveaxis(wide[:, wide_index[:, f]], 0, 1)
                # Sum over the sign patterns (s_B[0] = +1) by doubling: 2^b - 2 additions per
                # coefficient instead of b 2^(b-1) multiply-adds.
                w[:, 0] = z[0]
                h = 1
                for j in range(1, b):
                    np.subtract(w[:, :h], z[j][:, None], out=w[:, h:2 * h])
                    w[:, :h] += z[j][:, None]
                    h *= 2
        with np.errstate(invalid="ignore", over="ignore"):
            bound = (1.0 + VERTEX_TOL) * np.abs(det_f)
            biggest = np.abs(w[0])
            for k in range(1, r):
                np.maximum(biggest, np.abs(w[k]), out=biggest)
            inside = (biggest <= bound) & (det_f != 0)
        yield w, det_f, inside


def slice_max_norm_minors(generators: ArrayLike, *, rows) -> FloatArray:
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

    """
    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    batch = g.shape[:-2]
    rows = list(rows)
    r = m - len(rows)
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    part = flat[:, rows, :]
    size = np.max(np.abs(part), axis=(-2, -1))
    size = np.where(size > 0, size, 1.0)
    scaled = flat.copy()
    scaled[:, rows, :] = part / size[:, None, None]      # |G_R s| computed near 1: no under/overflow
    a = linalg.components(scaled)                         # (m, n, N)
    best = np.full(flat.shape[0], -1.0)
    for lo in range(0, flat.shape[0], SECTION_BLOCK):
        block = best[lo:lo + SECTION_BLOCK]
        for w, det, inside in section_candidates_minors(a[..., lo:lo + SECTION_BLOCK], rows):
            norm2 = w[r] * w[r]
            for i in range(r + 1, m):
                norm2 += w[i] * w[i]
            largest = np.max(np.where(inside, norm2, -1.0), axis=0)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                largest = np.where(largest >= 0, largest / (det * det), -1.0)
            np.fmax(block, largest, out=block)                     # an overflowed candidate (nan) never wins
    out = np.where(finite & (best >= 0), size * np.sqrt(np.maximum(best, 0.0)), np.nan)
    return out.reshape(batch)


def slice_max_norm_section(generators: ArrayLike, *, rows) -> FloatArray:
    """``wrench_slices.slice_max_norm`` in numpy passes over blocks of points, before ``kernels.section``.

    Verbatim but for the names: the candidates are today's ``wrench_slices._section_candidates``
    (with the free sets' rounding bounds), which ``slice_vertices`` still uses.
    """
    from metrics.wrench_slices import _section_candidates

    block_points = 4096         # one free set's candidates of a block stay within about a megabyte

    g = as_jacobian(generators, "generators")
    m, n = g.shape[-2:]
    batch = g.shape[:-2]
    rows = list(rows)
    r = m - len(rows)
    flat = g.reshape((-1, m, n))
    finite = np.all(np.isfinite(flat), axis=(-2, -1))
    flat = np.where(finite[:, None, None], flat, 0.0)
    part = flat[:, rows, :]
    size = np.max(np.abs(part), axis=(-2, -1))
    size = np.where(size > 0, size, 1.0)
    scaled = flat.copy()
    scaled[:, rows, :] = part / size[:, None, None]      # |G_R s| computed near 1: no under/overflow
    a = linalg.components(scaled)                         # (m, n, N)
    best = np.full(flat.shape[0], -1.0)
    for lo in range(0, flat.shape[0], block_points):
        block = best[lo:lo + block_points]
        norm2 = spare = None
        for w, det, inside in _section_candidates(a[..., lo:lo + block_points], rows):
            if norm2 is None:
                norm2, spare = np.empty(w.shape[1:]), np.empty(w.shape[1:])
            with np.errstate(invalid="ignore", over="ignore"):
                np.multiply(w[r], w[r], out=norm2)
                for i in range(r + 1, m):
                    norm2 += np.multiply(w[i], w[i], out=spare)
                largest = np.max(norm2, axis=0, where=inside, initial=-1.0)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                largest = np.where(largest >= 0, largest / (det * det), -1.0)
            np.fmax(block, largest, out=block)                     # an overflowed candidate (nan) never wins
    out = np.where(finite & (best >= 0), size * np.sqrt(np.maximum(best, 0.0)), np.nan)
    return out.reshape(batch)
