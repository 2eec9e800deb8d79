"""Issue 23, section 4: the printed claims of docs/printed_claims.md, each against an independent computation.

``scripts/printed_claims.py`` computes every figure of the page through the library (maps,
``metrics.quantities.evaluate``, ``metrics.orientations``, the ``isoforce`` command line). Here
the same figures come another way: the five-bar from circle intersections and paper 002's own
J_p and J_theta, closed-form 2 x 2 singular values, integrals by QUADPACK's adaptive rule, sample
counts by brute force and exact arithmetic, the Inverse3's isotropic force straight from its
kinematics. The page itself must be the script's output.
"""
from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

import mpmath
import numpy as np
import pytest
from scipy import integrate

from resources import load_preset
from scripts import paper_data as P
from scripts import printed_claims as PC

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "printed_claims.md"


@pytest.fixture(scope="module")
def results():
    return PC.compute()


def test_page_is_the_scripts_output(results):
    assert PAGE.read_text(encoding="utf-8") == PC.render(results), \
        "docs/printed_claims.md is stale: run python scripts/printed_claims.py --out docs/printed_claims.md"


# ------------------------------------------------------------------------------------------
# Paper 000: the share within mean +- SD
# ------------------------------------------------------------------------------------------

def _slice_points(grid) -> np.ndarray:
    """Table 3's slice (axes x, z; y fixed) as points (n, 3), m."""
    (x, z), y = grid.coordinates(), dict(grid.fixed)["y"]
    xx, zz = np.meshgrid(x, z, indexing="ij")
    return np.stack([xx.ravel(), np.full(xx.size, y), zz.ravel()], axis=-1)


def _inverse3_columns(preset_key: str, resolution: int | None = None):
    """Feasible slice points (n, 3) and the Jacobian (n, 3, 3) from the Inverse3's kinematics alone."""
    preset = load_preset(preset_key)
    mech = preset.mechanism
    grid = preset.grid if resolution is None else preset.grid.with_resolution(resolution)
    pts = _slice_points(grid)
    q, ok = mech.inverse(pts)
    ok[ok] = mech.feasible(q[ok], pts[ok])
    return pts[ok], mech.jacobian(q[ok], pts[ok])


def _isotropic(jac: np.ndarray, torques: np.ndarray) -> np.ndarray:
    """Radius of the largest ball in {f : |J[:, u] . f| <= t_u}: the nearest facet, min_u t_u / |J[:, u]|."""
    return np.min(torques / np.linalg.norm(jac, axis=-2), axis=-1)


def _share(values: np.ndarray, weights: np.ndarray | None = None) -> tuple[float, float, float]:
    """Mean, SD and share within mean +- SD, by sorting (counts from searchsorted, not a mask)."""
    if weights is None:
        mean, sd = math.fsum(values) / values.size, float(np.std(values, ddof=1))
        s = np.sort(values)
        inside = np.searchsorted(s, mean + sd, side="right") - np.searchsorted(s, mean - sd, side="left")
        return mean, sd, inside / values.size
    w = weights / math.fsum(weights)
    mean = math.fsum(w * values)
    sd = math.sqrt(math.fsum(w * (values - mean) ** 2))
    order = np.argsort(values)
    cum = np.concatenate([[0.0], np.cumsum(w[order])])
    s = values[order]
    return mean, sd, cum[np.searchsorted(s, mean + sd, side="right")] - cum[np.searchsorted(s, mean - sd, side="left")]


def test_paper000_shares_from_the_kinematics(results):
    """The three scenarios share the geometry; only the torque limits differ."""
    pts, jac = _inverse3_columns(P.TABLE3_SCENARIOS[0])
    for key, ours, skew in results.p000.scenarios:
        values = _isotropic(jac, load_preset(key).mechanism.torque_limits())
        mean, sd, share = _share(values)
        assert ours.count == values.size == 374_823
        assert ours.mean == pytest.approx(mean, rel=1e-12) and ours.sd == pytest.approx(sd, rel=1e-10)
        assert ours.share == pytest.approx(share, abs=2.0 / values.size)
        m2, m3 = np.mean((values - values.mean()) ** 2), np.mean((values - values.mean()) ** 3)
        assert skew == pytest.approx(m3 / m2 ** 1.5, rel=1e-9)
    s1 = results.p000.scenarios[0][1]
    assert round(100 * s1.share, 1) == 71.7            # the measurement


def test_paper000_shape_and_samplings(results):
    p0 = results.p000
    pts, jac = _inverse3_columns(P.TABLE3_SCENARIOS[0])
    values = _isotropic(jac, load_preset(P.TABLE3_SCENARIOS[0]).mechanism.torque_limits())
    # The normal rule, by quadrature of the density.
    normal = integrate.quad(lambda x: math.exp(-x * x / 2) / math.sqrt(2 * math.pi), -1.0, 1.0)[0]
    assert p0.normal == pytest.approx(normal, abs=1e-12)
    # Moments of the distribution, from their definitions.
    c = values - values.mean()
    m2, m3, m4 = (np.mean(c ** k) for k in (2, 3, 4))
    assert p0.skewness == pytest.approx(m3 / m2 ** 1.5, rel=1e-9)
    assert p0.excess_kurtosis == pytest.approx(m4 / m2 ** 2 - 3.0, rel=1e-9)
    assert p0.median == pytest.approx(np.median(values), rel=1e-12) and p0.median < p0.scenarios[0][1].mean
    # The gamma of that skewness: shape 4 / g^2, share by integrating its density.
    k = 4.0 / p0.skewness ** 2
    pdf = lambda x: math.exp((k - 1) * math.log(x) - x - math.lgamma(k))  # noqa: E731
    gamma = integrate.quad(pdf, max(0.0, k - math.sqrt(k)), k + math.sqrt(k), epsabs=1e-13)[0]
    assert p0.gamma_shape == pytest.approx(k, rel=1e-12) and p0.gamma == pytest.approx(gamma, abs=1e-9)
    # Revolved volume: weight |x|. Uniform joint samples: weight |x| / |det J| of the 3 x 3 Jacobian,
    # which is 1 / |det| of the five-bar block the script uses (the base column is (-c, x, 0)).
    x = np.abs(pts[:, 0])
    assert p0.volume.share == pytest.approx(_share(values, x)[2], abs=1e-9)
    assert p0.joint_space.share == pytest.approx(_share(values, x / np.abs(np.linalg.det(jac)))[2], abs=1e-9)
    for n, rung in p0.ladder:
        if n < 1000:
            _, jac_n = _inverse3_columns(P.TABLE3_SCENARIOS[0], n)
            v = _isotropic(jac_n, load_preset(P.TABLE3_SCENARIOS[0]).mechanism.torque_limits())
            assert rung.count == v.size and rung.share == pytest.approx(_share(v)[2], abs=1.0 / v.size)


# ------------------------------------------------------------------------------------------
# Paper 002: an independent five-bar (circle intersections, the paper's J_p and J_theta)
# ------------------------------------------------------------------------------------------

A1, A2, A3 = P.PAPER_OPTIMUM


def _elbows_out(c: np.ndarray, a1=A1, a2=A2, a3=A3) -> tuple[np.ndarray, np.ndarray]:
    """Elbows (n, 2, 2) of the elbows-out pose at points ``c`` (n, 2), and whether both legs reach.

    B_i is where the circle of radius a1 about the base joint O_i meets the circle of radius a2
    about C; elbows out puts B_1 counter-clockwise of O_1 -> C and B_2 clockwise of O_2 -> C. A point on
    the reach boundary to rounding (the circles tangent within 1e-12 a1^2) is reached, as the library's is.
    """
    legs, ok = [], np.ones(len(c), bool)
    for base, side in ((np.array([-a3, 0.0]), 1.0), (np.array([a3, 0.0]), -1.0)):
        d = c - base
        rho = np.hypot(d[:, 0], d[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):     # C on a base joint: unreachable, masked
            along = (a1 * a1 - a2 * a2 + rho * rho) / (2.0 * rho)
            across_sq = a1 * a1 - along * along
            e = d / rho[:, None]
        ok &= across_sq >= -1e-12 * a1 * a1
        normal = np.stack([-e[:, 1], e[:, 0]], axis=-1)
        legs.append(base + along[:, None] * e + side * np.sqrt(np.maximum(across_sq, 0.0))[:, None] * normal)
    return np.stack(legs, axis=1), ok


def _paper_jacobian(c: np.ndarray, b: np.ndarray, a3=A3) -> np.ndarray:
    """adj(J_p) J_theta (n, 2, 2): paper 002's J_p xdot = J_theta qdot solved for xdot, up to det J_p."""
    bases = np.array([[-a3, 0.0], [a3, 0.0]])
    p = c[:, None, :] - b                                   # rows of J_p: C - B_i
    link = b - bases                                        # B_i - O_i = a1 (cos q_i, sin q_i)
    jtheta = p[..., 0] * -link[..., 1] + p[..., 1] * link[..., 0]
    adj = np.stack([np.stack([p[:, 1, 1], -p[:, 0, 1]], -1), np.stack([-p[:, 1, 0], p[:, 0, 0]], -1)], -2)
    return adj * jtheta[:, None, :]


def _condition(c: np.ndarray, a1=A1, a2=A2, a3=A3) -> tuple[np.ndarray, np.ndarray]:
    """Condition number of J at points (n, 2) (scale-free, so adj(J_p) J_theta will do), and reach."""
    b, ok = _elbows_out(c, a1, a2, a3)
    m = _paper_jacobian(c[ok], b[ok], a3)
    # 2 x 2 singular values in closed form: (s1 + s2) / 2 and |s1 - s2| / 2 with
    # s1 = |(m00 - m11, m01 + m10)| and s2 = |(m00 + m11, m01 - m10)|.
    s1 = np.hypot(m[:, 0, 0] - m[:, 1, 1], m[:, 0, 1] + m[:, 1, 0])
    s2 = np.hypot(m[:, 0, 0] + m[:, 1, 1], m[:, 0, 1] - m[:, 1, 0])
    k = np.full(len(c), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):      # a singular J: K = inf
        k[ok] = (s1 + s2) / np.abs(s1 - s2)
    return k, ok


def _line(fn, y: float):
    return lambda x: float(fn(np.array([[x, y]]))[0])


def _mean_on(fn, y: float, a: float, b: float) -> float:
    """Mean of fn along the line at height y over [a, b] by QUADPACK's adaptive Gauss-Kronrod rule with
    extrapolation (QAGS), which integrates the 1 / sqrt growth of K at a boundary singularity; split at
    the middle so that each piece has at most one singular end."""
    mid = 0.5 * (a + b)
    f = _line(fn, y)
    pieces = [integrate.quad(f, lo, hi, limit=400, epsabs=0.0, epsrel=1e-11) for lo, hi in ((a, mid), (mid, b))]
    return sum(v for v, _ in pieces) / (b - a)


def _k(points):
    return _condition(points)[0]


def test_fig8_segments_by_hand(results):
    f8 = results.fig8
    # y = 3 cm: the near leg folds (|C - O| = a2 - a1 = 5 cm) at x = 3 + 4 = 7 cm; the far leg stretches
    # (|C - O| = 25 cm) at x = sqrt(625 - 9) - 3 cm. y = 18 cm: stretched at +-(sqrt(625 - 324) - 3) cm.
    out3, out18 = (math.sqrt(0.25 ** 2 - y * y) - 0.03 for y in (0.03, 0.18))
    assert np.ravel(f8.edge_segments) == pytest.approx([-out3, -0.07, 0.07, out3], abs=1e-15)
    assert np.ravel(f8.centre_segments) == pytest.approx([-out18, out18], abs=1e-15)
    assert not f8.mid_edge_reachable and not _elbows_out(np.array([[0.0, 0.03]]))[1][0]


def test_fig8_ratios_by_quadpack(results):
    f8 = results.fig8
    out3, out18 = (math.sqrt(0.25 ** 2 - y * y) - 0.03 for y in (0.03, 0.18))
    k3, k18 = _mean_on(_k, 0.03, 0.07, out3), _mean_on(_k, 0.18, 0.0, out18)   # symmetric about x = 0
    assert f8.k_edge == pytest.approx(k3, rel=1e-6) and f8.k_centre == pytest.approx(k18, rel=1e-6)
    assert f8.ratio == pytest.approx(k3 / k18, rel=1e-6)
    inv = lambda p: 1.0 / _k(p)  # noqa: E731
    assert f8.inverse_ratio == pytest.approx(
        integrate.quad(_line(inv, 0.18), 0.0, out18)[0] / out18
        / (integrate.quad(_line(inv, 0.03), 0.07, out3)[0] / (out3 - 0.07)), rel=1e-6)
    assert f8.common_range == pytest.approx((0.07, out18), abs=1e-15)
    assert f8.common_ratio == pytest.approx(_mean_on(_k, 0.03, 0.07, out18) / _mean_on(_k, 0.18, 0.07, out18),
                                            rel=1e-6)

    def isotropic(points):          # equal joint torques: min over the columns of 1 / |J[:, u]|
        b, _ = _elbows_out(points)
        m = _paper_jacobian(points, b)
        det = np.linalg.det(np.stack([points - b[:, 0], points - b[:, 1]], axis=1))
        return np.min(np.abs(det)[:, None] / np.linalg.norm(m, axis=-2), axis=-1)

    force = (integrate.quad(_line(isotropic, 0.18), 0.0, out18, limit=200)[0] / out18) / \
        (integrate.quad(_line(isotropic, 0.03), 0.07, out3, limit=200)[0] / (out3 - 0.07))
    assert f8.force_ratio == pytest.approx(force, rel=1e-6)
    assert f8.ratio < 1.5 and f8.force_ratio < 1.0


def test_fig8_grid_rows(results):
    """The 1 mm rows y = 30 and 180 mm of the preset's map (what `isoforce map` writes), regular points only."""
    x, ys = load_preset("fivebar_singh").grid.coordinates()
    means, counts = [], []
    for y in (ys[30], ys[180]):
        k, ok = _condition(np.stack([x, np.full_like(x, y)], axis=-1))
        k = k[ok & (k < 1e6)]            # the fold's two end points are singular (K = inf in the library)
        means.append(k.mean())
        counts.append(k.size)
    assert results.fig8.grid_points == tuple(counts) == (296, 287)
    assert results.fig8.grid_ratio == pytest.approx(means[0] / means[1], rel=1e-9)


def test_fig8_uniform_samplings(results):
    """Uniform samples of both lines over the map's x range; singular samples left out."""
    for h, ratio in results.fig8.uniform:
        x = np.linspace(-0.26, 0.26, int(round(0.52 / h)) + 1)
        means = []
        for y in (0.03, 0.18):
            k, ok = _condition(np.stack([x, np.full_like(x, y)], axis=-1))
            means.append(k[ok & (k < 1e6)].mean())
        assert ratio == pytest.approx(means[0] / means[1], rel=1e-9)
    assert max(v for _, v in results.fig8.uniform) < 1.5


# ------------------------------------------------------------------------------------------
# Paper 002: conditions (a)-(e)
# ------------------------------------------------------------------------------------------

def test_conditions_of_the_optimum_in_whole_numbers(results):
    c = results.conditions
    # r_i = 3 a_i / (a1 + a2 + a3) with (10, 15, 3) cm: 30/28, 45/28, 9/28.
    assert c.r == pytest.approx((30 / 28, 45 / 28, 9 / 28), rel=1e-15)
    assert c.holds == {"a": 9 > 30, "b": 45 > 30 + 9, "c": 9 < 30 + 45, "d": 45 != 9,
                       "e": 30 + 45 + 9 == 84 and 0 < 30 < 84 and 0 < 45 < 84 and 2 * 9 < 84}
    counts = dict.fromkeys("abcde", 0)
    for a1, a2, a3 in itertools.product(range(9, 13), range(11, 16), range(3, 6)):   # cm; the r_i scale out
        s = a1 + a2 + a3
        for key, ok in {"a": a3 > a1, "b": a2 > a1 + a3, "c": a3 < a1 + a2, "d": a2 != a3,
                        "e": 0 < 3 * a1 < 3 * s and 0 < 3 * a2 < 3 * s and 2 * 3 * a3 < 3 * s}.items():
            counts[key] += ok
    assert c.table1 == counts and counts["a"] == 0
    assert c.table1_above == sum(a2 >= a1 for a1, a2, _ in itertools.product(range(9, 13), range(11, 16), range(3, 6)))


def test_elbows_coincide_only_below_the_base(results):
    """Brute force: end-effectors C on the circle of radius a2 about B = (0, +-h) whose elbows-out pose puts
    both elbows at B. The highest lies just below the script's closed form, under the base line."""
    h = math.sqrt(A1 ** 2 - A3 ** 2)
    phi = np.linspace(0.0, 2.0 * np.pi, 200_001)
    best = -np.inf
    for sign in (1.0, -1.0):
        b = np.array([0.0, sign * h])
        c = b + A2 * np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        elbows, ok = _elbows_out(c)
        both = ok & np.all(np.linalg.norm(elbows - b, axis=-1) < 1e-9, axis=-1)
        best = max(best, c[both, 1].max(initial=-np.inf))
    assert best < results.conditions.coincidence_y < 0.0
    assert results.conditions.coincidence_y - best < A2 * 2 * np.pi / 200_000
    assert results.conditions.coincidence_y == pytest.approx(-0.0477, abs=5e-5)


def test_no_direct_singularity_on_the_map(results):
    """The smallest |sin| of the angle between the distal links over the preset's feasible grid points."""
    grid = load_preset("fivebar_singh").grid
    x, y = grid.coordinates()
    xx, yy = np.meshgrid(x, y, indexing="ij")
    c = np.stack([xx.ravel(), yy.ravel()], axis=-1)
    b, ok = _elbows_out(c)
    p = c[ok, None, :] - b[ok]
    sine = np.abs(p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]) / A2 ** 2
    assert results.conditions.min_distal_sine == pytest.approx(sine.min(), rel=1e-9)
    assert results.conditions.singular["direct"] == results.conditions.singular["combined"] == 0
    assert sum(results.conditions.singular.values()) == ok.sum()


# ------------------------------------------------------------------------------------------
# Paper 002: the dexterous annulus
# ------------------------------------------------------------------------------------------

def _annulus_share(design, nr: int, nphi: int, *, highest_ill: bool = False):
    """Area share of the reachable annulus 0.9 L .. 1.7 L (upper half) with K < 5, on cell-centred polar nodes;
    with ``highest_ill`` also the largest y (units of L) of a reached node with K >= 5."""
    length = sum(design) / 3.0
    a1, a2, a3 = (v / length for v in design)
    r = np.linspace(0.9, 1.7, 2 * nr + 1)[1::2]
    phi = np.linspace(0.0, np.pi, 2 * nphi + 1)[1::2]
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    c = np.stack([(rr * np.cos(pp)).ravel(), (rr * np.sin(pp)).ravel()], axis=-1)
    k, ok = _condition(c, a1, a2, a3)
    w = rr.ravel()
    share = float(np.sum(w[ok & (k < 5.0)]) / np.sum(w[ok]))
    return (share, float(c[ok & ~(k < 5.0), 1].max(initial=-np.inf))) if highest_ill else share


def test_annulus_shares(results):
    an = results.annulus
    nr, nphi = PC.POLAR_FINE
    share, ill = _annulus_share(P.PAPER_OPTIMUM, nr, nphi, highest_ill=True)
    assert an.optimum.share == pytest.approx(share, abs=1e-9) and an.optimum.ill_below == pytest.approx(ill, abs=1e-12)
    assert 0.0 < ill < 0.1            # a sliver next to the base line
    assert an.equal.share == pytest.approx(_annulus_share((1.0, 1.0, 1.0), nr, nphi), abs=1e-9)
    assert 0.999 < an.optimum.share < 1.0 and an.optimum.reachable == pytest.approx(1.0, abs=1e-12)
    assert an.equal_conditions == {"a": False, "b": False, "c": True, "d": False, "e": True}
    # The Table 1 sweep on its own nodes, and the count at the 98 % line on nodes twice as fine.
    mine = np.array([_annulus_share(d, *PC.POLAR_SWEEP) for d in P.table1_designs()])
    np.testing.assert_allclose(an.table1, mine, rtol=0, atol=1e-9)
    near = np.abs(mine - PC.DEXTEROUS_SHARE) < 0.005
    finer = np.array([_annulus_share(d, 2 * PC.POLAR_SWEEP[0], 2 * PC.POLAR_SWEEP[1])
                      for d in P.table1_designs()[near]])
    assert np.array_equal(finer >= PC.DEXTEROUS_SHARE, mine[near] >= PC.DEXTEROUS_SHARE)
    assert np.count_nonzero(mine >= PC.DEXTEROUS_SHARE) == 31


def test_annulus_on_the_normalised_arcs(results):
    """Equal links on Table 1's normalised arcs: rings at 0.01, 0.03, ... L, 180 points each at 0.5, 1.5, ... deg."""
    r = (np.arange(150) + 0.5) * 0.02
    phi = np.radians(np.arange(180) + 0.5)
    rr, pp = np.meshgrid(r[(r >= 0.9) & (r <= 1.7)], phi, indexing="ij")
    k, ok = _condition(np.stack([(rr * np.cos(pp)).ravel(), (rr * np.sin(pp)).ravel()], axis=-1), 1.0, 1.0, 1.0)
    share, count = results.annulus.equal_arcs
    assert count == ok.sum() and share == pytest.approx(np.count_nonzero(ok & (k < 5)) / ok.sum(), abs=1e-12)


def test_annulus_legend_of_equal_links(results):
    """The bands figure's legend for a1 = a2 = a3 = 100 mm on the preset's 1 mm grid, counted here."""
    grid = load_preset("fivebar_singh").grid
    x, y = grid.coordinates()
    xx, yy = np.meshgrid(x, y, indexing="ij")
    c = np.stack([xx.ravel(), yy.ravel()], axis=-1)
    r, length = np.hypot(c[:, 0], c[:, 1]), (0.1 + 0.1 + 0.1) / 3.0
    inside = (r >= 0.9 * length) & (r <= 1.7 * length)
    k, ok = _condition(c[inside], 0.1, 0.1, 0.1)
    assert f"K < 5 at {100 * np.count_nonzero(ok & (k < 5)) / ok.sum():.0f} % of its {ok.sum()} feasible pts" \
        in results.annulus.equal_grid
    # Its direct singular points: the two distal links on one line (|sin| of their angle at rounding level).
    b, ok = _elbows_out(c, 0.1, 0.1, 0.1)
    p = c[ok, None, :] - b[ok]
    aligned = np.abs(p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]) / 0.1 ** 2 < 1e-6
    r = np.hypot(*c[ok][aligned].T) / 0.1
    assert results.annulus.equal_direct == (aligned.sum(), pytest.approx(r.min(), abs=1e-12),
                                            pytest.approx(r.max(), abs=1e-12))
    assert r == pytest.approx(1.0, abs=1e-12)


# ------------------------------------------------------------------------------------------
# Paper 001: eq. 16's example
# ------------------------------------------------------------------------------------------

def _kr_float(bound: float, n_rings: int) -> int:
    """Eq. 16 as printed, left to right in double precision."""
    return 1 + sum(math.floor((2 * math.pi * n_rings / bound) * math.sin(n * bound / n_rings))
                   for n in range(1, n_rings + 1))


def _kr_exact(bound_deg: int, n_rings: int) -> int:
    """Eq. 16 in 40-digit arithmetic; a term within 1e-30 of an integer is that integer (Niven: sin 30 deg)."""
    mpmath.mp.dps = 40
    tb = mpmath.pi * bound_deg / 180
    total = 1
    for n in range(1, n_rings + 1):
        x = 2 * mpmath.pi * n_rings / tb * mpmath.sin(n * tb / n_rings)
        nearest = mpmath.nint(x)
        total += int(nearest if abs(x - nearest) < mpmath.mpf("1e-30") else mpmath.floor(x))
    return total


def test_eq16_counts(results):
    e = results.eq16
    t45 = math.radians(45.0)
    assert e.float_counts == tuple(_kr_float(t45, n) for n in range(1, 5)) == (6, 18, 34, 58)
    assert e.exact_counts == tuple(_kr_exact(45, n) for n in range(1, 5)) == (6, 18, 35, 58)
    # Table II's 168 (30 deg, N = 7) fixes the order: eq. 16 left to right gives it, 2 pi / dtheta_2,n does not.
    d1 = math.radians(30.0) / 7
    eq14 = 1 + sum(math.floor(2 * math.pi / (d1 / math.sin(n * d1))) for n in range(1, 8))
    assert e.table2_orders == (_kr_float(math.radians(30.0), 7), eq14) == (168, 169)


def test_eq16_orders_differ_only_on_exact_integer_terms():
    """What the page says of the evaluation order: the two orders floor differently only where
    n bound / N = 30 deg, the term that is an integer in exact arithmetic."""
    for deg in (30, 45):
        tb = math.radians(deg)
        for big_n in range(1, 31):
            d1 = tb / big_n
            for n in range(1, big_n + 1):
                a = math.floor((2 * math.pi * big_n / tb) * math.sin(n * tb / big_n))
                b = math.floor(2 * math.pi / (d1 / math.sin(n * d1)))
                assert a == b or n * deg == 30 * big_n, (deg, big_n, n)


def test_eq16_no_reading_gives_eight(results):
    e = results.eq16
    assert e.variants == math.prod(len(v) for v in PC.EQ16_VARIANTS.values()) == 144
    assert e.best[:2] == ((6, 18, 34, 58), 3) and e.first_two == 0
    # However N = 2's two terms (6.12, 11.31) are rounded, with or without the pole: 17 to 20, never 8.
    terms = [(2 * math.pi * 2 / math.radians(45)) * math.sin(n * math.radians(45) / 2) for n in (1, 2)]
    assert e.n2_terms == pytest.approx(tuple(terms), rel=1e-15)
    sums = {pole + f(terms[0]) + g(terms[1]) for pole in (0, 1) for f in (math.floor, round, math.ceil)
            for g in (math.floor, round, math.ceil)}
    assert min(sums) == 17 and max(sums) == 20
    # No tip bound (0.01 deg steps) gives K_r = 6 at N = 1 and 8 at N = 2.
    n2 = set()
    for centi in range(1, 18000):
        tb = math.radians(centi / 100)
        if _kr_float(tb, 1) == 6:
            n2.add(_kr_float(tb, 2))
    assert e.bounds_scanned == 17999 and e.n2_with_six == tuple(sorted(n2)) and 8 not in n2


# ------------------------------------------------------------------------------------------
# Paper 001: the half-workspace count
# ------------------------------------------------------------------------------------------

def test_half_workspace_count(results):
    h = results.half
    assert 2 ** 2 * 3 ** 3 * 5 * 17 ** 3 == PC.HALF_PRINTED and h.factors == "2^2 * 3^3 * 5 * 17^3"
    assert h.half == 9 * 11 * 11 * 168 * 13 == 2_378_376 and 17 * 11 * 11 * 168 * 13 == 4_492_488
    assert h.planes == pytest.approx(2_653_020 / (11 * 11 * 168 * 13), rel=1e-15)
    # The same family by brute force, tip counts from eq. 16 here (both floor rules, N = 1..30).
    i_counts = [33, 65, 17, 33, 9, 17, 5, 9]            # 0..8 and -8..8 cm at 0.25, 0.5, 1, 2 cm
    jk_counts = [41, 21, 11, 6]                          # -5..5 cm at the same steps
    tips = {_kr_float(math.radians(30.0), n) for n in range(1, 31)} | {_kr_exact(30, n) for n in range(1, 31)}
    rolls = [int(round(60 / s)) + 1 for s in PC.ROLL_STEPS] + [1]
    totals = [a * b * b * t * r for a, b, t, r in itertools.product(i_counts, jk_counts, tips, rolls)]
    assert h.family == len(totals) and PC.HALF_PRINTED not in totals and not h.hits
    assert h.nearest[0][0] == min(totals, key=lambda t: abs(t - PC.HALF_PRINTED))


# ------------------------------------------------------------------------------------------
# docs/sensor_resolution.md: the command runs and prints that page's optima
# ------------------------------------------------------------------------------------------

def test_sensor_cli_prints_the_pages_table(results):
    s = results.sensor
    assert s.status == 0
    text = (ROOT / "docs" / "sensor_resolution.md").read_text(encoding="utf-8")
    rows = {float(m[1]): (m[2], m[3]) for m in
            re.finditer(r"^\| (\d+) \| [^|]+ \| ([^|]+) \| [^|]+ \| ([^|]+) \|", text, flags=re.M)}
    assert sorted(rows) == [d for d, _, _ in s.optima]
    for distance, ratio, value in s.optima:
        if ratio is None:
            assert rows[distance] == ("n/a", "no design reaches") and value is None
        else:
            assert rows[distance] == (f"{ratio:.2f}", f"{value:.3f}")
    assert "fails when it prints" not in text
