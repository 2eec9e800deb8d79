"""The PHANToM's joint-space mass matrix from its bodies against the source's own closed form.

``mahilab/Phantom`` (commit ff342f9ab24b5844b70609f4912cdf00c6c3fc1d) publishes ``M(Q)`` in
``cpp/src/PhantomModel.cpp:101-116``, generated symbolically by ``matlab/dynamics.m`` from the
body data of ``PhantomModel.hpp:12-30``. Its expressions are transcribed below (C++ ``pow(c, 2.0)``
written ``c**2``, ``Ic_a.xx`` written ``I_a_xx``); they exclude the rotors. Our ``M`` is built by the
generic body code (``kinematics.dynamics``) from the same body data, so agreement tests the body
frames, the kinetic-energy assembly and the central differences at once.
"""
from __future__ import annotations

import numpy as np
import pytest

from kinematics.bodies import FD_STEP
from kinematics.serial_rrr import SerialRRR

# PhantomModel.hpp:12-30 (Tensor stores xx, xy, xz, yy, yz, zz).
m_a, m_c, m_be, m_df, m_g = 0.026220, 0.026146, 0.267840, 0.215420, 0.361590
# Ic_* as (xx, xy, xz, yy, yz, zz); matlab/dynamics.m builds the tensor [xx -xy -xz; -xy yy -yz; ...].
A = (6.029e-05, 0, 0, 5.7e-07, 0, 6.004e-05)
C = (0.00013177, 0, 0, 8.9e-07, 0, 0.00013138)
BE = (0.0001133, 4.1e-07, -2.296e-05, 0.00091667, 4.8e-07, 0.00082222)
DF = (0.0001214, -3.2e-07, -7.45e-06, 0.00026133, 3.23e-06, 0.00015823)
G = (0.0015202, 5.838e-05, 0.00018147, 0.0012112, 0.00023832, 0.00093887)
P_a_x, P_a_y, P_a_z = 0.000024230000000, -0.052378920000000, 0
P_c_x, P_c_y, P_c_z = 0, 0.104777390000000, 0
P_be_x, P_be_y, P_be_z = -0.035188750000000, -0.000062800000000, 0.002324160000000
P_df_x, P_df_y, P_df_z = -0.051535410000000, 0.000609030000000, 0.004028730000000
P_g_x, P_g_y, P_g_z = -0.010485630000000, 0.013963870000000, -0.053808270000000
l1, l3 = 0.209550, 0.031750
J_mot, ETA = 1.08e-06, (13.3, 11.2, 11.2)          # PhantomModel.hpp:68, :50


def mahilab_mass_matrix(q1, q2, q3, inertia_factor=1.0, products=True):
    """``PhantomModel.cpp:101-116`` ``M(Q)``, transcribed; inertias scaled by ``inertia_factor``
    and their products of inertia dropped with ``products=False`` (the masses and centres kept)."""
    k, p = inertia_factor, (inertia_factor if products else 0.0)
    I_a_xx, I_a_xy, I_a_xz, I_a_yy, I_a_yz, I_a_zz = k*A[0], p*A[1], p*A[2], k*A[3], p*A[4], k*A[5]
    I_c_xx, I_c_xy, I_c_xz, I_c_yy, I_c_yz, I_c_zz = k*C[0], p*C[1], p*C[2], k*C[3], p*C[4], k*C[5]
    I_be_xx, I_be_xy, I_be_xz, I_be_yy, I_be_yz, I_be_zz = k*BE[0], p*BE[1], p*BE[2], k*BE[3], p*BE[4], k*BE[5]
    I_df_xx, I_df_xy, I_df_xz, I_df_yy, I_df_yz, I_df_zz = k*DF[0], p*DF[1], p*DF[2], k*DF[3], p*DF[4], k*DF[5]
    I_g_zz = k*G[5]
    s2, c2, s3, c3 = np.sin(q2), np.cos(q2), np.sin(q3), np.cos(q3)
    s23, c23 = np.sin(q2 - q3), np.cos(q2 - q3)
    M = [[0.0] * 3 for _ in range(3)]
    M[0][0] = I_a_xx+I_c_yy+I_g_zz+I_be_xx+I_df_yy+(P_a_y*P_a_y)*m_a+(P_a_z*P_a_z)*m_a+(P_be_y*P_be_y)*m_be+(P_be_z*P_be_z)*m_be+(P_c_x*P_c_x)*m_c+(P_c_z*P_c_z)*m_c+(P_df_x*P_df_x)*m_df+(P_df_z*P_df_z)*m_df+(P_g_x*P_g_x)*m_g+(P_g_y*P_g_y)*m_g+(l3*l3)*m_c-I_a_xx*c3**2+I_c_xx*c2**2+I_a_yy*c3**2-I_c_yy*c2**2-I_be_xx*c2**2+I_be_yy*c2**2+I_df_xx*c3**2-I_df_yy*c3**2-I_a_xy*np.sin(2*q3)+I_c_xy*np.sin(2*q2)-I_be_xy*np.sin(2*q2)+I_df_xy*np.sin(2*q3)+(P_a_x*P_a_x)*m_a*c3**2-(P_a_y*P_a_y)*m_a*c3**2+(P_be_x*P_be_x)*m_be*c2**2-(P_be_y*P_be_y)*m_be*c2**2-(P_c_x*P_c_x)*m_c*c2**2+(P_c_y*P_c_y)*m_c*c2**2-(P_df_x*P_df_x)*m_df*c3**2+(P_df_y*P_df_y)*m_df*c3**2+(l1*l1)*m_a*c2**2-(l3*l3)*m_c*c3**2-P_a_x*P_a_y*m_a*np.sin(2*q3)+P_c_x*P_c_y*m_c*np.sin(2*q2)-P_be_x*P_be_y*m_be*np.sin(2*q2)+P_df_x*P_df_y*m_df*np.sin(2*q3)+P_a_x*l1*m_a*c2*c3*2.0-P_a_y*l1*m_a*c2*s3*2.0+P_c_y*l3*m_c*c2*s3*2.0+P_c_x*l3*m_c*s2*s3*2.0  # noqa: E501
    M[0][1] = -I_a_yz*c3+I_c_xz*c2-I_be_yz*c2+I_df_xz*c3-I_a_xz*s3-I_c_yz*s2-I_be_xz*s2-I_df_yz*s3+P_c_x*P_c_z*m_c*c2-P_be_y*P_be_z*m_be*c2-P_c_y*P_c_z*m_c*s2-P_be_x*P_be_z*m_be*s2-P_a_z*l1*m_a*s2  # noqa: E501
    M[0][2] = -I_a_yz*c3+I_c_xz*c2-I_a_xz*s3-I_c_yz*s2-P_a_y*P_a_z*m_a*c3+P_df_x*P_df_z*m_df*c3-P_a_x*P_a_z*m_a*s3-P_df_y*P_df_z*m_df*s3+P_c_z*l3*m_c*c3  # noqa: E501
    M[1][0] = M[0][1]
    M[1][1] = I_a_zz+I_c_zz+I_be_zz+I_df_zz+(P_be_x*P_be_x)*m_be+(P_be_y*P_be_y)*m_be+(P_c_x*P_c_x)*m_c+(P_c_y*P_c_y)*m_c+(l1*l1)*m_a  # noqa: E501
    M[1][2] = I_a_zz+I_c_zz+P_a_x*l1*m_a*c23+P_c_x*l3*m_c*c23+P_a_y*l1*m_a*s23-P_c_y*l3*m_c*s23
    M[2][0] = M[0][2]
    M[2][1] = M[1][2]
    M[2][2] = I_a_zz+I_c_zz+(P_a_x*P_a_x)*m_a+(P_a_y*P_a_y)*m_a+(P_df_x*P_df_x)*m_df+(P_df_y*P_df_y)*m_df+(l3*l3)*m_c
    return np.array(M, float)


def _poses(count: int, seed: int) -> np.ndarray:
    """Random feasible joint angles of the default PHANToM (limits and coupling limits)."""
    mech = SerialRRR()
    rng = np.random.default_rng(seed)
    lo, hi = np.array(mech.params.lower_limits), np.array(mech.params.upper_limits)
    q = rng.uniform(lo, hi, size=(20 * count, 3))
    x, _ = mech.forward(q)
    return q[mech.feasible(q, x)][:count]


BODIES = ("a", "c", "be", "df", "g")
SOURCE = dict(zip(BODIES, (A, C, BE, DF, G)))


def _with(inertias) -> SerialRRR:
    """The default PHANToM with other inertia tensors (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) per body."""
    return SerialRRR().replace(**{f"inertia_{b}": inertias[b] for b in BODIES})


def _assert_close(ours, theirs):
    # Central differences of unit-size rotations: truncation ~ h^2 and rounding ~ eps / h,
    # both ~ FD_STEP^2 ~ 4e-11 relative per Jacobian entry; products of two such entries summed
    # over five bodies keep that order. 100x margin over the entries' scale |M|.
    scale = np.abs(theirs).max(axis=(-1, -2))[..., None, None]
    assert np.all(np.abs(ours - theirs) <= 100 * FD_STEP**2 * scale)


def test_the_bodies_placement_reproduces_the_sources_mass_matrix_without_rotational_inertia():
    # Masses and centres only: every term of M is m |v_c|^2, which the source differentiates
    # symbolically from its forward kinematics (compute_energies.m: jacobian(P0ci, Q)).
    q = _poses(200, seed=1)
    assert len(q) == 200
    ours = _with({b: (0.0,) * 6 for b in BODIES}).mass_matrix(q, rotors=False)
    theirs = np.array([mahilab_mass_matrix(*row, inertia_factor=0.0) for row in q])
    _assert_close(ours, theirs)


def test_the_sources_yaw_inertia_m00_agrees_with_every_tensor_entry():
    # M[0, 0] is the inertia about the base axis: the body's yaw rate q1dot is carried through
    # each frame correctly in the source, so all six entries of every tensor must agree.
    q = _poses(200, seed=4)
    ours = SerialRRR().mass_matrix(q, rotors=False)[:, 0, 0]
    theirs = np.array([mahilab_mass_matrix(*row)[0, 0] for row in q])
    _assert_close(ours[:, None, None], theirs[:, None, None])


def test_the_sources_mass_matrix_counts_the_wrong_rate_for_three_bodies_spin():
    """A finding, not a match: the source's M(Q) is off by the spin inertias of bodies a, c and df.

    ``compute_energies.m`` gives DH frame i the angular velocity ``R w_(i-1) + Qd(i) Z``, the
    i-th joint's rate, but ``dynamics.m`` turns link 2 (a) by ``q3 - q2``, the drum (df) by
    ``q3 - pi/2`` and the follower (c) by ``q2 - q3``: in truth a and df spin at ``q3dot``, c
    and link 1 (be) at ``q2dot`` about the shoulder axis, as the parallelogram requires. With the
    source's rates, M[1, 1] gains ``Izz_a + Izz_df``, M[1, 2] gains ``Izz_a + Izz_c`` and M[2, 2]
    gains ``Izz_c - Izz_df``. With the products of inertia zeroed (so no cross term mixes the
    yaw rate in), that is the whole difference: 2.2e-4, 1.9e-4 and -2.7e-5 kg m^2 against
    diagonal entries of 2.7e-3 and 8.9e-4 kg m^2 (8 % and 3 %).
    """
    q = _poses(200, seed=5)
    diagonal = {b: (v[0], v[3], v[5], 0.0, 0.0, 0.0) for b, v in SOURCE.items()}
    ours = _with(diagonal).mass_matrix(q, rotors=False)
    theirs = np.array([mahilab_mass_matrix(*row, products=False) for row in q])
    zz = {b: v[5] for b, v in SOURCE.items()}
    wrong_rates = np.zeros((3, 3))
    wrong_rates[1, 1] = zz["a"] + zz["df"]
    wrong_rates[1, 2] = wrong_rates[2, 1] = zz["a"] + zz["c"]
    wrong_rates[2, 2] = zz["c"] - zz["df"]
    _assert_close(ours + wrong_rates, theirs)


def test_rotors_add_their_inertia_times_the_ratio_squared_on_the_diagonal():
    mech = SerialRRR()
    q = _poses(20, seed=2)
    diff = mech.mass_matrix(q) - mech.mass_matrix(q, rotors=False)
    expected = np.diag([J_mot * r**2 for r in ETA])
    # The difference of two sums that share every other term: a few ulps of |M|.
    scale = np.abs(mech.mass_matrix(q)).max()
    assert np.allclose(diff, expected, rtol=0, atol=16 * np.finfo(float).eps * scale)


@pytest.mark.parametrize("k", [2.0**-40, 0.5, 3.0, 2.0**40])
def test_body_masses_and_inertias_times_k_scale_the_link_mass_matrix_by_k(k):
    mech = SerialRRR()
    p = mech.params
    scaled = mech.replace(link_masses=tuple(k * m for m in p.link_masses),
                          **{f"inertia_{b}": tuple(k * v for v in getattr(p, f"inertia_{b}"))
                             for b in ("a", "c", "be", "df", "g")})
    q = _poses(10, seed=3)
    a, b = mech.mass_matrix(q, rotors=False), scaled.mass_matrix(q, rotors=False)
    # M is linear in the masses and inertias; a power of two scales exactly, another k within
    # a few roundings of each of the ~10 terms of an entry.
    tol = 0 if np.log2(k) == round(np.log2(k)) else 32 * np.finfo(float).eps
    assert np.all(np.abs(b - k * a) <= tol * k * np.abs(a).max())
