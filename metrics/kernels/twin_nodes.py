"""Two of the redundant Twin-Pantograph's graph steps on its ``J`` (``twin_rows``), compiled point by point.

``metrics.quantity_nodes`` forms them in numpy over the whole batch, one (N, 5, 6) temporary per
operation and a BLAS call per point for each product (numpy's ``matmul`` of a stack):

- ``scaled_gram``: ``scaled_condition``'s Gram matrix ``M M^T`` of the scaled ``M = S_T J``, and
  whether ``M`` is finite and within ``SAFE_SCALE`` (else the point goes to LAPACK);
- ``lost_points``: ``unbounded_where_lost``'s test, the residual ``max |J A^T - I|`` against
  ``64 n eps |J|_F |A|_F`` (a pose singular to machine precision).

Each product's entries are summed as ``matmul`` sums them (``facets.fma``: the same bits on this
machine's BLAS). The residual test does not rest on that: a residual within ``MARGIN`` of its bound
(the two orders' rounding, derived at ``MARGIN``) is left undecided, and numpy decides those
points. CPU per point, one thread, load 3-4, Twin-Pantograph: the Gram matrices 0.17 us against
numpy's 0.52; the residual test 0.1 us against 0.3. The points run on the calling thread
(``nogil``): a map's chunks already run in parallel threads.
"""
from __future__ import annotations

import numpy as np

from .facets import fma
from .jit import jit

EPS = 2.220446049250313e-16
#: ``lost_points`` leaves a residual within ``MARGIN n eps |J|_F |A|_F`` of its bound to numpy.
#: Derivation: an entry of ``J A^T`` is an n-term dot product; summed in any order its error is at
#: most ``gamma_n sum_u |J_iu A_ju| <= gamma_n |J|_F |A|_F`` (Cauchy-Schwarz), ``gamma_n = n eps /
#: (1 - n eps)``, so two orders differ by at most ``2 gamma_n |J|_F |A|_F``; ``- I`` and ``abs`` add
#: at most one rounding of the entry (``eps`` relative, the entry at most about ``|J|_F |A|_F + 1``).
#: The bound ``64 n eps |J|_F |A|_F`` itself moves by a few ulps between summation orders of the
#: norms (30 squares: ``30 eps`` relative, ``64 n eps`` times that, negligible). So two orders'
#: decisions can differ only within ``(2 gamma_n + 2 eps) |J|_F |A|_F``, about ``(2 n + 2) eps``;
#: ``MARGIN n eps`` with 16 is 96 eps for n = 6, six times that. Sums of squares below ``TINY``
#: (entries whose squares underflow lose their relative accuracy) are left to numpy too.
MARGIN = 16.0
#: ``2^-1022`` (the smallest normal) times ``2^52`` times 30 terms, rounded down to a power of 2.
TINY = 2.0 ** -960


@jit(allocates=True)
def scaled_gram(jac, scale, lo, hi, gram, good):
    """``M M^T`` (N, m, m) of ``M = diag(scale) J`` and whether ``M`` is finite with ``lo < max |M| < hi``.

    Parameters
    ----------
    jac : ndarray, shape (N, m, n)
        ``J``.
    scale : ndarray, shape (m,)
        ``S_T``'s diagonal (``wrenches.task_row_scale``).
    lo, hi : float
        ``linalg.SAFE_SCALE``.
    gram : ndarray, shape (N, m, m)
        Filled: ``matmul``'s bits (``facets.fma``); zeros where not ``good`` (numpy's
        ``np.where(good, M, 0) @ ...``).
    good : ndarray of bool, shape (N,)
        Filled: finite and within the safe scale (``linalg.outside_safe_scale`` of ``max |M|``).
    """
    n_pts, m, n = jac.shape
    s = np.empty((m, n))
    for p in range(n_pts):
        finite = True
        big = 0.0
        for i in range(m):
            for u in range(n):
                e = jac[p, i, u] * scale[i]
                s[i, u] = e
                if not np.isfinite(e):
                    finite = False
                elif abs(e) > big:
                    big = abs(e)
        ok = finite and big > lo and big < hi
        good[p] = ok
        for i in range(m):
            for j in range(i, m):
                acc = 0.0
                if ok:
                    for u in range(n):
                        acc = fma(s[i, u], s[j, u], acc)
                gram[p, i, j] = acc
                gram[p, j, i] = acc            # fma(a, b, c) = fma(b, a, c): numpy's is symmetric too


@jit(allocates=True)
def lost_points(jac, gen, t, lost, undecided):
    """``unbounded_where_lost``'s test per point: ``max |J A^T - I| > 64 n eps |J|_F |A|_F``, ``A = G / t``.

    Parameters
    ----------
    jac : ndarray, shape (N, m, n)
        ``J``.
    gen : ndarray, shape (N, m, n)
        The generators ``G = A diag(t)`` (``reference_forces``).
    t : ndarray, shape (n,)
        The rated torque limits (``A = G / t``, numpy's division).
    lost : ndarray of bool, shape (N,)
        Filled: the pose is singular to machine precision (residual beyond its bound, or not finite).
    undecided : ndarray of bool, shape (N,)
        Filled: numpy decides (an entry not finite, or the residual within ``MARGIN`` of its bound).
    """
    n_pts, m, n = jac.shape
    a = np.empty((m, n))
    for p in range(n_pts):
        lost[p] = False
        undecided[p] = False
        finite = True
        sj = 0.0
        sa = 0.0
        for i in range(m):
            for u in range(n):
                e = gen[p, i, u] / t[u]
                a[i, u] = e
                if not (np.isfinite(e) and np.isfinite(jac[p, i, u])):
                    finite = False
                sj += jac[p, i, u] * jac[p, i, u]
                sa += e * e
        if not finite:
            undecided[p] = True
            continue
        residual = 0.0
        for i in range(m):
            for j in range(m):
                acc = 0.0
                for u in range(n):
                    acc = fma(jac[p, i, u], a[j, u], acc)
                diff = abs(acc - 1.0) if i == j else abs(acc)
                if diff > residual:
                    residual = diff
        size = np.sqrt(sj) * np.sqrt(sa)
        bound = 64.0 * n * EPS * size
        margin = MARGIN * n * EPS * size
        if (not (sj > TINY and sa > TINY and np.isfinite(size) and np.isfinite(residual))
                or abs(residual - bound) <= margin):
            undecided[p] = True
            continue
        lost[p] = residual > bound
