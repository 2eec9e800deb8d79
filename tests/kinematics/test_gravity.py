"""Gravity on the PHANToM's links (``kinematics.gravity``, ``SerialRRR`` mass model).

References, each independent of the code under test:

- central differences of the potential energy ``V(q)`` (the torque is ``dV/dq``), and of the
  centres of mass (their analytic Jacobians);
- the source's own gravity vector and potential energies, ``G(Q)`` and ``U(Q)`` of
  ``mahilab/Phantom`` ``cpp/src/PhantomModel.cpp`` (upright: gravity along -z of frame {0}),
  written out below from the formulas printed there;
- the links as drawn (``link_points``): each centre of mass sits on its link where the
  source's body-frame coordinates put it;
- hand sums of weight times lever arm at the home pose ``q = 0``.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.fivebar import FiveBar
from kinematics.gravity import MOUNTINGS, STANDARD_GRAVITY, check_gravity, gravity_vector
from kinematics.serial_rrr import BODIES, SerialRRR

MECH = SerialRRR()
P = MECH.params
M_A, M_C, M_BE, M_DF, M_G = P.link_masses
EPS = float(np.finfo(float).eps)
G0 = STANDARD_GRAVITY


def _random_q(rng, k):
    """Joint angles anywhere (V is smooth everywhere; limits do not matter to the calculus)."""
    return rng.uniform(-np.pi, np.pi, size=(k, 3))


def _bound():
    """``B = |g| sum_i m_i (2 (l1 + l3) + 3 |c_i|_1)``, J: bounds |V| and every partial derivative of it.

    Each coordinate of a centre of mass is a sum of terms (a length) x (products of sines and
    cosines of single joint angles, frequency 1): the link offsets ``l1``, ``l3`` and the body
    coordinates ``c_i`` of the source, each appearing in at most the radial and one other
    coordinate. Differentiating any such term in one angle, any number of times, keeps its
    amplitude, so ``|d^k V / dq_j^k| <= |g| sum_i m_i (sum of those amplitudes) <= B``.
    """
    com = np.array([P.com_a, P.com_c, P.com_be, P.com_df, P.com_g])
    return G0 * float(np.sum(np.asarray(P.link_masses) * (2 * (P.link1_length + P.crank_length)
                                                          + 3 * np.abs(com).sum(axis=1))))


def _central_tolerance(h: float) -> float:
    """Central-difference error bound for a function bounded with its derivatives by ``_bound()``.

    Truncation ``h^2 / 6 max|f'''|``; rounding: V is a sum of about 60 rounded products, each
    within a few eps of its (bounded by B) size, so V carries at most ``30 eps B`` absolute
    error and the quotient ``(V+ - V-) / 2h`` at most ``30 eps B / h``.
    """
    b = _bound()
    return b * (h * h / 6.0 + 30.0 * EPS / h)


# -- the mountings -----------------------------------------------------------------------------
def test_mountings_point_gravity_down_the_named_axis():
    assert gravity_vector("upright") == (0.0, 0.0, -G0)
    assert gravity_vector("inverted") == (0.0, 0.0, G0)
    for name, up in MOUNTINGS.items():
        g = np.array(gravity_vector(name))
        assert np.linalg.norm(g) == pytest.approx(G0, rel=EPS)
        assert float(g @ np.array(up)) == pytest.approx(-G0, rel=EPS)     # opposite the axis that is up


def test_bad_gravity_and_mounting_are_named():
    with pytest.raises(ValueError, match="mounting must be one of upright"):
        gravity_vector("sideways")
    with pytest.raises(ValueError, match="gravity must be 3 finite numbers"):
        check_gravity([0.0, 9.81])
    with pytest.raises(ValueError, match="gravity must be 3 finite numbers"):
        MECH.gravity_torque([0.0, 0.0, 0.0], [0.0, np.nan, -9.81])


def test_a_model_without_masses_says_so():
    mech = FiveBar()
    assert not mech.has_mass_model
    with pytest.raises(ValueError, match="FiveBar has no mass model"):
        mech.gravity_torque([0.1, 0.2], gravity_vector("upright"))
    with pytest.raises(ValueError, match="FiveBar has no mass model"):
        mech.potential_energy([0.1, 0.2], gravity_vector("upright"))


# -- calculus ----------------------------------------------------------------------------------
@pytest.mark.parametrize("gravity", [*(gravity_vector(n) for n in MOUNTINGS), (3.0, -4.0, 7.5)])
def test_gravity_torque_is_the_gradient_of_the_potential_energy(gravity):
    rng = np.random.default_rng(7)
    q = _random_q(rng, 40)
    h = 2e-5          # about (90 eps)^(1/3): balances the two terms of _central_tolerance
    tau = MECH.gravity_torque(q, gravity)
    numeric = np.empty_like(tau)
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        numeric[:, j] = (MECH.potential_energy(q + step, gravity) - MECH.potential_energy(q - step, gravity)) / (2 * h)
    scale = np.linalg.norm(gravity) / G0           # _bound() is for |g| = g0
    assert np.max(np.abs(tau - numeric)) <= _central_tolerance(h) * scale
    # The test has teeth: the torques are far above the tolerance.
    assert np.max(np.abs(tau)) > 1e4 * _central_tolerance(h) * scale


def test_centre_of_mass_jacobian_matches_central_differences():
    rng = np.random.default_rng(8)
    q = _random_q(rng, 25)
    h = 2e-5
    jac = MECH.centres_of_mass_jacobian(q)
    assert jac.shape == (25, 5, 3, 3)
    # Lengths bounded by L = 2 (l1 + l3) + 3 max |c_i|_1 with all derivatives (as in _bound()):
    # error <= L (h^2 / 6 + 30 eps / h).
    com = np.array([P.com_a, P.com_c, P.com_be, P.com_df, P.com_g])
    length = 2 * (P.link1_length + P.crank_length) + 3 * np.abs(com).sum(axis=1).max()
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        numeric = (MECH.centres_of_mass(q + step) - MECH.centres_of_mass(q - step)) / (2 * h)
        assert np.max(np.abs(jac[..., j] - numeric)) <= length * (h * h / 6 + 30 * EPS / h)


def test_batch_equals_one_at_a_time():
    rng = np.random.default_rng(9)
    q = _random_q(rng, 6).reshape(2, 3, 3)
    g = (1.0, -2.0, -9.0)
    batch = MECH.gravity_torque(q, g)
    assert batch.shape == (2, 3, 3)
    for idx in np.ndindex(2, 3):
        assert np.array_equal(batch[idx], MECH.gravity_torque(q[idx], g))


def test_gravity_is_linear_in_g():
    rng = np.random.default_rng(10)
    q = _random_q(rng, 10)
    up = MECH.gravity_torque(q, gravity_vector("upright"))
    # Negating g negates every product exactly: bit for bit.
    assert np.array_equal(MECH.gravity_torque(q, gravity_vector("inverted")), -up)


# -- against the source ------------------------------------------------------------------------
def _source_g(q):
    """``G(Q)`` of PhantomModel.cpp (gravity along -z of frame {0}), term by term."""
    s2, c2, s3, c3 = np.sin(q[:, 1]), np.cos(q[:, 1]), np.sin(q[:, 2]), np.cos(q[:, 2])
    a, c, be, df = P.com_a, P.com_c, P.com_be, P.com_df
    l1, l3 = P.link1_length, P.crank_length
    g2 = G0 * (-be[1] * M_BE * s2 + c[0] * M_C * s2 + l1 * M_A * c2 + be[0] * M_BE * c2 + c[1] * M_C * c2)
    g3 = G0 * (-a[1] * M_A * s3 + df[0] * M_DF * s3 + l3 * M_C * s3 + a[0] * M_A * c3 + df[1] * M_DF * c3)
    return np.stack([np.zeros_like(g2), g2, g3], axis=-1)


def _source_u(q):
    """``sum U(Q)`` of PhantomModel.cpp: the five bodies' potential energies (upright), J."""
    s2, c2, s3, c3 = np.sin(q[:, 1]), np.cos(q[:, 1]), np.sin(q[:, 2]), np.cos(q[:, 2])
    a, c, be, df, gg = P.com_a, P.com_c, P.com_be, P.com_df, P.com_g
    l1, l3 = P.link1_length, P.crank_length
    return G0 * (gg[2] * M_G + M_BE * (be[1] * c2 + be[0] * s2) + M_A * (a[1] * c3 + a[0] * s3 + l1 * s2)
                 - M_DF * (df[0] * c3 - df[1] * s3) - M_C * (c[0] * c2 - c[1] * s2 + l3 * c3))


def test_upright_gravity_matches_the_source_model():
    rng = np.random.default_rng(11)
    q = _random_q(rng, 50)
    g = gravity_vector("upright")
    # Both are sums of the same ~6 products in another order: within 16 eps of the bound B.
    tol = 16 * EPS * _bound()
    assert np.max(np.abs(MECH.gravity_torque(q, g) - _source_g(q))) <= tol
    assert np.max(np.abs(MECH.potential_energy(q, g) - _source_u(q))) <= tol


def test_centres_of_mass_sit_on_the_drawn_links():
    """Each body's centre where its body-frame coordinates put it along the links as drawn.

    ``link_points``: tip, elbow, shoulder, crank end, follower joint. Link 2's centre lies
    ``-y_a`` from the elbow towards the tip, link 1's ``x_be`` along link 1 from the shoulder
    (negative: behind it, a counterweight), the drum's ``x_df`` along the crank, the follower's
    ``y_c`` along the follower from the crank end; the other two coordinates are offsets across
    the link, so the distance to that point is their norm.
    """
    rng = np.random.default_rng(12)
    q = _random_q(rng, 30)
    pts = MECH.link_points(q)
    tip, elbow, shoulder, crank, follower = (pts[:, k] for k in range(5))
    com = MECH.centres_of_mass(q)

    def unit(v):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    cases = {
        "a": (elbow, unit(tip - elbow), -P.com_a[1], np.hypot(P.com_a[0], P.com_a[2])),
        "be": (shoulder, unit(elbow - shoulder), P.com_be[0], np.hypot(P.com_be[1], P.com_be[2])),
        "df": (shoulder, unit(crank - shoulder), P.com_df[0], np.hypot(P.com_df[1], P.com_df[2])),
        "c": (crank, unit(follower - crank), P.com_c[1], np.hypot(P.com_c[0], P.com_c[2])),
    }
    for body, (origin, direction, along, across) in cases.items():
        i = BODIES.index(body)
        expected = origin + along * direction
        # The offset across the link is exactly ``across`` long (a rotation keeps lengths);
        # 1e-15 m covers the rounding of coordinates below 0.4 m.
        assert np.allclose(np.linalg.norm(com[:, i] - expected, axis=-1), across, rtol=0, atol=1e-15), body


def test_home_pose_by_hand():
    """At q = 0 (link 1 horizontal forward, link 2 hanging straight down), upright.

    Shoulder (q2): turning q2 moves link 1, the follower and link 2 (translated with the
    elbow, since q3 is absolute); the lever arms are their horizontal distances ahead of the
    shoulder axis that q2 swings: link 1's centre ``x_be`` (behind it), the elbow ``l1`` for
    link 2, the follower's centre ``y_c`` (it runs parallel to link 1 from the crank end, which
    is straight below the shoulder). Holding them takes ``g (m_be x_be + m_a l1 + m_c y_c)``.
    Elbow drive (q3): link 2 and the drum hang straight down; only their offsets ``x_a`` and
    ``y_df`` across the vertical give a lever arm. Base (q1): the base axis is vertical, so
    gravity has no moment about it.
    """
    tau = MECH.gravity_torque([0.0, 0.0, 0.0], gravity_vector("upright"))
    l1 = P.link1_length
    shoulder = G0 * (M_BE * P.com_be[0] + M_A * l1 + M_C * P.com_c[1])
    elbow = G0 * (M_A * P.com_a[0] + M_DF * P.com_df[1])
    assert tau[0] == 0.0
    assert tau[1] == pytest.approx(shoulder, rel=8 * EPS)
    assert tau[2] == pytest.approx(elbow, rel=8 * EPS)
    # The numbers: the counterweighted shoulder needs only -11.7 mN m; the elbow 1.29 mN m.
    assert round(float(tau[1]), 6) == -0.01168
    assert round(float(tau[2]), 7) == 0.0012928


def test_wall_mounted_base_torque_by_hand():
    """``x-up`` at q = 0: gravity along -x, horizontal and in the arm's plane. About the base
    axis (now horizontal), each body's weight acts at its offset across the arm's plane
    (+y): the moving bodies' ``-z_i`` (their z axes point along -y at q1 = 0), the turret's
    ``y_g``. Turning q1 by dq moves a point at y = s by -s dq along x, against gravity when s > 0.
    """
    tau = MECH.gravity_torque([0.0, 0.0, 0.0], gravity_vector("x-up"))
    com = {b: c for b, c in zip(BODIES, (P.com_a, P.com_c, P.com_be, P.com_df, P.com_g))}
    masses = dict(zip(BODIES, P.link_masses))
    offsets = {b: -com[b][2] for b in ("a", "c", "be", "df")} | {"g": com["g"][1]}
    # V = -sum m g . p = g0 sum m x; dx/dq1 = -y, so dV/dq1 = -g0 sum m y.
    expected = -G0 * sum(masses[b] * offsets[b] for b in BODIES)
    assert tau[0] == pytest.approx(expected, rel=16 * EPS)
