"""The sensor-resolution (velocity) GII, paper 001 eqs. 23-27 (``metrics.sensor_gii.velocity_*``).

Against a by-hand 2 x 2, a brute-force search over unit hand velocities, an explicitly formed
per-matrix product, central differences of the Twin-Pantograph's inverse kinematics, and the
invariances the index must have. Headless; every random draw uses a fixed seed.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics import TwinPantograph
from metrics import gii as G
from metrics import sensor_gii as SG

RNG_SEED = 20261201
EPS = np.finfo(float).eps


def _by_hand_2x2(mat):
    """2 x 2 singular values by hand: (s1 +- s2)^2 = |M|_F^2 +- 2 |det M|."""
    fro2 = np.sum(mat * mat, axis=(-2, -1))
    det = mat[..., 0, 0] * mat[..., 1, 1] - mat[..., 0, 1] * mat[..., 1, 0]
    plus, minus = np.sqrt(fro2 + 2 * np.abs(det)), np.sqrt(np.maximum(fro2 - 2 * np.abs(det), 0.0))
    return (plus + minus) / 2, (plus - minus) / 2


def test_velocity_singular_values_of_a_2x2_by_hand():
    k = np.array([[[2.0, -1.0], [0.5, 3.0]], [[1.0, 0.2], [0.0, 0.1]]])     # rad/m, rad/rad
    res, vel = np.array([1.6, 1.0]), np.array([5.0, 30.0])
    m = np.diag(res / res[0]) @ k @ np.diag(vel / vel[0])                 # formed explicitly: S_J K S_T
    s1, s2 = _by_hand_2x2(m)
    sv = SG.velocity_singular_values(k, res, vel)
    # the by-hand formula loses ~eps * s1^2 / s2 in s2 (a difference of nearly equal roots)
    tol = 16 * EPS * s1 * (1.0 + s1 / s2)
    assert np.all(np.abs(sv[:, 0] - s1) <= tol) and np.all(np.abs(sv[:, 1] - s2) <= tol)
    assert np.allclose(SG.velocity_scaled_matrix(k, res, vel), m, rtol=4 * EPS, atol=0.0)


def test_velocity_gii_against_brute_force_over_unit_hand_velocities():
    rng = np.random.default_rng(RNG_SEED)
    k = rng.normal(size=(7, 3, 2))                      # 7 samples, 3 joints, 2 task directions
    res, vel = np.array([1.0, 1.7, 0.6]), np.array([5.0, 30.0])
    m = np.diag(res) @ k @ np.diag(vel / vel[0])        # R normalised by R_1 = 1
    h = np.pi / 200_000
    theta = np.arange(0.0, np.pi, h)
    u = np.stack([np.cos(theta), np.sin(theta)])        # unit normalised hand velocities (2, T)
    norms2 = np.sum((m @ u) ** 2, axis=-2)              # |M u|^2, (7, T)
    lo, hi = np.sqrt(norms2.min(-1)), np.sqrt(norms2.max(-1))
    sv = SG.velocity_singular_values(k, res, vel)
    # |M u(theta)|^2 = A + B cos(2 (theta - theta0)), B = (s1^2 - s2^2) / 2; a grid point lies
    # within h / 2 of the extreme, so the squared extreme is off by at most B (1 - cos h) <= B h^2 / 2.
    b = (sv[:, 0] ** 2 - sv[:, 1] ** 2) / 2
    assert np.all(sv[:, 1] ** 2 <= lo ** 2 + 1e-12) and np.all(lo ** 2 - sv[:, 1] ** 2 <= b * h * h / 2 + 1e-12)
    assert np.all(hi ** 2 <= sv[:, 0] ** 2 + 1e-12) and np.all(sv[:, 0] ** 2 - hi ** 2 <= b * h * h / 2 + 1e-12)
    r = SG.velocity_gii(k, res, vel)
    brute = lo.min() / hi.max()
    assert r.kind == "velocity_map" and r.count == 7
    # the grid's min is above sigma_min and its max below sigma_max, each by the bounds above
    slack = b * h * h / 2
    upper = np.sqrt(sv[:, 1] ** 2 + slack).min() / np.sqrt(sv[:, 0] ** 2 - slack).max()
    assert r.value * (1 - 1e-12) <= brute <= upper * (1 + 1e-12)
    assert r.argmin == (int(np.argmin(lo)),) and r.argmax == (int(np.argmax(hi)),)
    assert r.weakest == r.argmin and r.strongest == r.argmax


def test_square_mechanism_gives_the_same_gii_from_our_jacobian():
    """K = J^-1: sigma(S_J K S_T) are the reciprocals of sigma(S_T^-1 J S_J^-1) (the 'jacobian' kind)."""
    rng = np.random.default_rng(RNG_SEED + 1)
    jac = rng.normal(size=(20, 3, 3)) + 3 * np.eye(3)
    k = np.linalg.inv(jac)
    res, vel = np.array([1.0, 1.6, 1.6]), np.array([5.0, 5.0, 30.0])
    sv = SG.velocity_singular_values(k, res, vel)
    recip = 1.0 / G.scaled_singular_values(jac, res, 1.0 / vel, kind="jacobian")[..., ::-1]
    assert np.allclose(sv, recip, rtol=1e-12)
    r = SG.velocity_gii(k, res, vel)
    g = G.gii(jac, res, 1.0 / vel, kind="jacobian")
    assert np.isclose(r.value, g.value, rtol=1e-12)
    assert r.weakest == g.weakest and r.strongest == g.strongest


def test_gii_does_not_depend_on_the_length_unit_but_the_literal_reading_does():
    """S_T multiplies (module doc): with K's translation columns in rad/cm and speeds in cm/s the
    index is the SI one; eq. 11 read literally (S_T^-1) changes with the unit."""
    rng = np.random.default_rng(RNG_SEED + 2)
    k_si = rng.normal(size=(9, 6, 5))
    k_cm = k_si.copy()
    k_cm[..., :3] /= 100.0                               # rad per cm
    res = np.array([1.6, 1, 1, 1.6, 1, 1])
    v_si, v_cm = np.array([5.0, 5, 5, 30, 30]), np.array([500.0, 500, 500, 30, 30])
    a, b = SG.velocity_gii(k_si, res, v_si).value, SG.velocity_gii(k_cm, res, v_cm).value
    assert np.isclose(a, b, rtol=1e-12)
    assert np.isclose(SG.velocity_scaled_matrix(k_cm, res, v_cm), SG.velocity_scaled_matrix(k_si, res, v_si) / 100,
                      rtol=1e-12).all()
    lit_si, lit_cm = (SG.velocity_gii(kk, res, 1.0 / vv).value for kk, vv in ((k_si, v_si), (k_cm, v_cm)))
    assert not np.isclose(lit_si, lit_cm, rtol=1e-3)


def test_invariances_common_factor_and_rotated_translation_rows():
    rng = np.random.default_rng(RNG_SEED + 3)
    k = rng.normal(size=(11, 6, 5))
    res, vel = np.array([1.6, 1, 1, 1.6, 1, 1]), np.array(G.HUMAN_HAND_VELOCITIES)[[0, 1, 2, 3, 5]]
    base = SG.velocity_gii(k, res, vel)
    # one factor on every resolution: the same value; Q on the shoulders is 1/Q on the waists
    assert SG.velocity_gii(k, 4000 * res, vel).value == pytest.approx(base.value, rel=1e-12)
    shoulders = np.array([1, 1 / 1.6, 1 / 1.6, 1, 1 / 1.6, 1 / 1.6])
    assert SG.velocity_gii(k, shoulders, vel).value == pytest.approx(base.value, rel=1e-12)
    # equal speeds on x, y, z: expressing the velocity in a rotated frame changes nothing
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    rot = k.copy()
    rot[..., :3] = k[..., :3] @ q
    assert np.allclose(SG.velocity_singular_values(rot, res, vel), SG.velocity_singular_values(k, res, vel),
                       rtol=1e-12)


def test_fewer_joints_than_task_directions_pad_zeros_and_singular_samples_give_zero():
    sv = SG.velocity_singular_values(np.ones((1, 2)), (1.0,), (1.0, 1.0))
    assert sv.tolist() == [np.sqrt(2.0), 0.0]
    k = np.stack([np.eye(2), np.array([[np.inf, 0.0], [0.0, 1.0]])])
    assert SG.velocity_gii(k, (1.0, 1.0), (1.0, 1.0)).value == 0.0
    r = SG.velocity_gii(k, (1.0, 1.0), (1.0, 1.0), feasible=np.array([True, False]))
    assert r.value == 1.0 and r.count == 1
    none = SG.velocity_gii(k, (1.0, 1.0), (1.0, 1.0), feasible=np.array([False, False]))
    assert np.isnan(none.value) and none.argmin is None


@pytest.mark.parametrize("args, word", [
    ((np.eye(2), (1.0, 1.0, 1.0), (1.0, 1.0)), "resolutions"),
    ((np.eye(2), (1.0, 1.0), (1.0,)), "velocities"),
    ((np.eye(2), (1.0, 0.0), (1.0, 1.0)), "resolutions"),
    ((np.eye(2), (1.0, 1.0), (1.0, -2.0)), "velocities"),
])
def test_bad_scalings_name_the_argument(args, word):
    with pytest.raises(ValueError, match=word):
        SG.velocity_singular_values(*args)
    with pytest.raises(ValueError, match=word):
        SG.velocity_gii(*args)


def test_twin_pantograph_velocity_map_against_central_differences():
    """K from the model (force_map transposed) against d(IK)/dx: dq/dx = K T(x), T = coordinate_rates_to_twist."""
    mech = TwinPantograph()
    x0 = np.array([[0.02, 0.01, 0.26, 0.3, -0.2], [-0.05, 0.03, 0.22, -0.5, 0.4], [0.0, 0.0, 0.25, 0.0, 0.0]])
    q0, ok = mech.inverse(x0)
    assert ok.all()
    k = np.swapaxes(mech.force_map(q0, x0), -1, -2)
    dq_dx = k @ mech.coordinate_rates_to_twist(x0)
    h = 1e-6
    fd = np.empty_like(dq_dx)
    for j in range(5):
        e = np.zeros(5)
        e[j] = h
        qp, _ = mech.inverse(x0 + e)
        qm, _ = mech.inverse(x0 - e)
        fd[..., j] = (qp - qm) / (2 * h)
    # central differences: truncation h^2 |q'''| / 6 with |q'''| ~ 1/L^3 (L ~ 0.1 m: 1e3) ~ 2e-10, rounding
    # eps |q| / h ~ 1e-9 (|q| <= 2 pi, IK a few operations deep): 1e-7 covers both with a margin
    assert np.allclose(fd, dq_dx, rtol=0.0, atol=1e-7 * (1 + np.abs(dq_dx)))
    res, vel = np.array([1.6, 1, 1, 1.6, 1, 1]), np.array([5.0, 5, 5, 30, 30])
    k_fd = fd @ np.linalg.inv(mech.coordinate_rates_to_twist(x0))
    assert np.allclose(SG.velocity_singular_values(k_fd, res, vel), SG.velocity_singular_values(k, res, vel),
                       rtol=1e-6)
