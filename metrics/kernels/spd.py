"""Inverses of surely regular symmetric positive definite matrices, compiled (``metrics.dynamics.inverse_spd``).

``sure_inverses`` takes a batch of m x m matrices (the task inertias of the 5- and 6-DOF devices)
and, for each one ``inverse_spd`` may invert directly, its inverse by Cholesky: ``A = L L^T``, ``A^-1
= L^-T L^-1`` (``kinematics.rotations.spd_inverse``'s order), symmetric. Cholesky's inverse is
backward stable like LU's (Higham, *Accuracy and Stability of Numerical Algorithms*, sec. 14.2:
``|X - A^-1| <= c m eps kappa |A^-1|`` with ``c`` small), and needs no pivoting for a positive
definite matrix; per matrix it is a few hundred flops in registers where numpy's ``inv`` and
``slogdet`` each make a LAPACK call.

"Surely regular" is ``inverse_spd``'s test: finite entries, the trace and the trace over m inside
``metrics.linalg.SAFE_SCALE``, and ``det > SURE_REGULAR m eps tr^m`` (then ``lambda_min /
lambda_max > SURE_REGULAR m eps``, far above the eigenvalues' rounding). The determinant is
``prod L_jj^2``, taken as ``prod (L_jj^2 / tr)`` against ``SURE_REGULAR m eps``: each factor is at
most 1 (``L_jj^2 <= a_jj <= tr``), so the product cannot overflow, and where it underflows it is far
below the threshold anyway. A matrix whose Cholesky meets a pivot that is not positive is not
surely regular. The others are the caller's (``inverse_spd``'s eigen-decomposition: ``inf`` along a
null direction, ``nan`` where not finite).
"""
from __future__ import annotations

import math

import numpy as np

from ..linalg import SAFE_SCALE, SURE_REGULAR
from .jit import jit

EPS = 2.220446049250313e-16
_LO, _HI = SAFE_SCALE


@jit()
def sure_inverses(mats, out, sure, low, inv_l):
    """``out[i] = mats[i]^-1`` where ``mats[i]`` is surely regular (``sure[i]``), else ``out[i]`` untouched.

    Parameters
    ----------
    mats : ndarray, shape (N, m, m)
        Symmetric (the lower triangle is read).
    out : ndarray, shape (N, m, m)
        The inverses, exactly symmetric, where ``sure``.
    sure : ndarray of bool, shape (N,)
        Filled: whether the matrix passed the test (module doc).
    low, inv_l : ndarray, shape (m, m)
        Scratch, zeros above the diagonal.
    """
    n_mat, m, _ = mats.shape
    floor = SURE_REGULAR * m * EPS
    for k in range(n_mat):
        a = mats[k]
        sure[k] = False
        finite = True
        for r in range(m):
            for c in range(m):
                if not np.isfinite(a[r, c]):
                    finite = False
        if not finite:
            continue
        tr = 0.0
        for j in range(m):
            tr += a[j, j]
        if not (tr > _LO and tr < _HI and tr / m > _LO and tr / m < _HI):
            continue
        ratio = 1.0
        good = True
        for j in range(m):
            d = a[j, j]
            for i in range(j):
                d -= low[j, i] * low[j, i]
            if not d > 0.0:
                good = False
                break
            ratio *= d / tr
            root = math.sqrt(d)
            low[j, j] = root
            for r in range(j + 1, m):
                acc = a[r, j]
                for i in range(j):
                    acc -= low[r, i] * low[j, i]
                low[r, j] = acc / root
        if not (good and ratio > floor):
            continue
        for j in range(m):
            inv_l[j, j] = 1.0 / low[j, j]
            for r in range(j + 1, m):
                acc = 0.0
                for i in range(j, r):
                    acc += low[r, i] * inv_l[i, j]
                inv_l[r, j] = -acc / low[r, r]
        for r in range(m):
            for c in range(r + 1):
                acc = inv_l[r, r] * inv_l[r, c]
                for i in range(r + 1, m):
                    acc += inv_l[i, r] * inv_l[i, c]
                out[k, r, c] = acc
                out[k, c, r] = acc
        sure[k] = True
