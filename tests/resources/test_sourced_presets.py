"""The presets taken from public sources (issue 9, sections 1-2) against what their sources state.

Each test says which figure it checks and where it comes from: the source's own formulas
re-typed from the pinned file (forward kinematics, J^T statics, the torque chain), or a figure
that follows from the source by hand at a pose where the Jacobian is simple. The Falcon's
maxima are decided by its singular loci (``kinematics.delta.Delta.singular_loci``).

Headless: numpy and the compute layer only. Fixed seeds.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import isotropic_force
from metrics.suprema import unbounded_suprema
from resources import load_preset

EPS = np.finfo(float).eps
DEG = np.pi / 180.0


def _provenance(key: str) -> dict:
    return dict(load_preset(key).provenance)


@pytest.mark.parametrize("key", ["woodenhaptics", "haply_2diy"])
def test_each_sourced_preset_names_its_source_and_its_estimates(key):
    prov = _provenance(key)
    assert prov["repository"].startswith("https://github.com/")
    assert len(prov["commit"]) == 40 and prov["path"]
    mech = load_preset(key).mechanism
    names = {info.name for info in (*mech.PARAM_INFO, *getattr(mech, "PRESET_PARAMS", ()))}
    estimated = prov["estimated"]
    assert set(estimated) <= names
    reasons = {k.split(".", 1)[1] for k in prov if k.startswith("estimates.")}
    for name in estimated:        # every estimate says why, in [source.estimates] (limits together)
        assert name in reasons or ("limits" in reasons and ("limits" in name or "_minus_" in name)), name
    assert any(k.startswith("datasheet.") for k in prov)


# -- WoodenHaptics: forsslund/woodenhaptics, CHAI3D extension, src/devices/CWoodenDevice.cpp ---------
WOODY = load_preset("woodenhaptics").mechanism
LN, LB, LC = 0.080, 0.205, 0.200                      # CWoodenDevice.cpp:92 length_body_a, _b, _c
ORIGIN = np.array([0.220, 0.0, 0.080])                # :94 workspace_origin
T_JOINT = 0.0603 * 3.0 * np.array([0.160, 0.120, 0.120]) / 0.010    # :95 kt x 3.0 A, :91/:93 diameters


def _woody_angles(n: int, seed: int) -> np.ndarray:
    """Source angles (tA, tB, tC) (n, 3), rad, spread over the estimated limits' range."""
    rng = np.random.default_rng(seed)
    return np.stack([rng.uniform(-0.7, 0.7, n), rng.uniform(-0.4, 1.2, n), rng.uniform(-1.2, 0.6, n)], -1)


def _to_q(t: np.ndarray) -> np.ndarray:
    """The preset's q = (tA, 90 deg - tB, 90 deg - (tB + tC)) (the header of woodenhaptics.toml)."""
    return np.stack([t[:, 0], np.pi / 2 - t[:, 1], np.pi / 2 - (t[:, 1] + t[:, 2])], -1)


def test_woodenhaptics_forward_kinematics_is_the_sources():
    """CWoodenDevice.cpp:683-685 (getPosition), re-typed, against the serial_rrr model shifted by the
    source's workspace origin; both are a few roundings of sums of products below 0.5 m: 16 eps m."""
    t = _woody_angles(500, seed=1)
    ta, tb, tc = t.T
    src = np.stack([np.cos(ta) * (LB * np.sin(tb) + LC * np.cos(tb + tc)) - ORIGIN[0],
                    np.sin(ta) * (LB * np.sin(tb) + LC * np.cos(tb + tc)) - ORIGIN[1],
                    LN + LB * np.cos(tb) - LC * np.sin(tb + tc) - ORIGIN[2]], -1)
    x, ok = WOODY.forward(_to_q(t))
    assert ok.all()
    assert np.max(np.abs((x - np.array([ORIGIN[0], 0.0, 0.0])) - src)) <= 16 * EPS


def test_woodenhaptics_statics_are_the_sources_up_to_the_angle_signs_and_one_entry():
    """The source's J (CWoodenDevice.cpp:850-861, with respect to (tA, tB, tB + tC)) gives the torques
    J^T F; ours are with respect to q, whose q2, q3 run against tB, tB + tC: the same torques with
    those two signs flipped. Products of lengths below 0.5 m and forces of 1 N: 16 eps N m.

    Except one entry: the source's dz/dtB (:859) is -Lb sin tB - Lc cos(tB + tC), the derivative with
    tC held, while its x and y rows (:853, :856, the -Lc sin term commented out) and its drive
    (motor C turns tB + tC, :621-635) hold tB + tC. Holding it, dz/dtB = -Lb sin tB; we use that
    (docs/devices.md says so), and the test puts it in before comparing."""
    t = _woody_angles(300, seed=2)
    ta, tb, tc = t.T
    jac = np.zeros((len(t), 3, 3))
    jac[:, 0, 0] = -np.sin(ta) * (LB * np.sin(tb) + LC * np.cos(tb + tc))
    jac[:, 0, 1] = np.cos(ta) * (LB * np.cos(tb))
    jac[:, 0, 2] = -LC * np.cos(ta) * np.sin(tb + tc)
    jac[:, 1, 0] = np.cos(ta) * (LB * np.sin(tb) + LC * np.cos(tb + tc))
    jac[:, 1, 1] = np.sin(ta) * (LB * np.cos(tb))
    jac[:, 1, 2] = -LC * np.sin(ta) * np.sin(tb + tc)
    jac[:, 2, 1] = -LB * np.sin(tb) - LC * np.cos(tb + tc)
    jac[:, 2, 2] = -LC * np.cos(tb + tc)
    source_entry = jac[:, 2, 1].copy()
    jac[:, 2, 1] = -LB * np.sin(tb)                     # tB + tC held, as in the other rows
    assert np.max(np.abs(source_entry - jac[:, 2, 1])) > 0.1 * LC   # the source's entry differs
    force = np.random.default_rng(3).uniform(-1.0, 1.0, (len(t), 3))
    src = np.einsum("kij,ki->kj", jac, force)
    ours = np.einsum("kij,ki->kj", WOODY.jacobian(_to_q(t)), force)
    assert np.max(np.abs(ours * np.array([1.0, -1.0, -1.0]) - src)) <= 16 * EPS


def test_woodenhaptics_joint_torques_are_the_sources_full_scale_command():
    """The source sends motor amps = joint torque x capstan / body / kt and clips the +-10 V signal at
    3.0 A (CWoodenDevice.cpp:882-895): the joint torque at full scale is 0.0603 x 3.0 x 16 (base) and
    x 12 (the others) = 2.8944, 2.1708, 2.1708 N m."""
    assert np.allclose(WOODY.torque_limits(), T_JOINT, rtol=4 * EPS, atol=0.0)
    assert np.allclose(T_JOINT, [2.8944, 2.1708, 2.1708], rtol=1e-12, atol=0.0)


def test_woodenhaptics_isotropic_force_at_the_sources_zero_pose_by_hand():
    """At the source's zero pose (tA = tB = tC = 0: body B straight up, body C straight out, tip at
    (Lc, 0, Ln + Lb) in its base frame) J is diagonal in (radial, tangential, up): the base moves the
    tip sideways at Lc per rad, body B moves it outwards at Lb, body C downwards at Lc. The largest
    force held in every direction is min(2.8944 / 0.200, 2.1708 / 0.205, 2.1708 / 0.200) =
    10.589 N (body B's motor), below the source's max_linear_force of 12 N (CWoodenDevice.cpp:96)."""
    q = _to_q(np.zeros((1, 3)))
    x, _ = WOODY.forward(q)
    assert np.allclose(x, [[LC, 0.0, LB]], rtol=0.0, atol=4 * EPS)
    jac = WOODY.jacobian(q)
    assert np.allclose(np.abs(jac), [[[0.0, LB, 0.0], [LC, 0.0, 0.0], [0.0, 0.0, LC]]], rtol=0.0, atol=4 * EPS)
    by_hand = min(T_JOINT[0] / LC, T_JOINT[1] / LB, T_JOINT[2] / LC)
    got = isotropic_force(jac, torque_limits=WOODY.torque_limits())
    assert np.allclose(got, by_hand, rtol=16 * EPS, atol=0.0)
    assert by_hand == pytest.approx(10.589268, abs=1e-6) and by_hand < 12.0


def test_woodenhaptics_estimated_limits_hold_the_sources_workspace_sphere():
    """The estimated limits contain the 100 mm workspace_radius sphere about the workspace origin
    (CWoodenDevice.cpp:94), as [source.estimates] says: 20000 points in the ball are all feasible."""
    rng = np.random.default_rng(4)
    v = rng.normal(size=(20000, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    x = np.array([0.220, 0.0, 0.0]) + 0.100 * rng.random((20000, 1)) ** (1 / 3) * v
    q, ok = WOODY.inverse(x)
    assert ok.all() and WOODY.feasible(q, x).all()


# -- Haply 2DIY gen 3: hAPI Pantograph.java (V3.0.0), hardware version 3 ------------------------------
HAPLY = load_preset("haply_2diy").mechanism
# hAPI's l (both proximal links), L (both distal links; its L1 = L2 = L) and d: Pantograph.java:39-42.
PROX, DIST, D = 0.07, 0.09, 0.038


def _hapi_forward(th1: np.ndarray, th2: np.ndarray):
    """Pantograph.java:63-117 forwardKinematics re-typed (float64): end-effector (k, 2) in the hAPI
    frame (motor 1 at the origin, motor 2 at (d, 0)) and JT (k, 2, 2), tau = JT f."""
    c1, c2, s1, s2 = np.cos(th1), np.cos(th2), np.sin(th1), np.sin(th2)
    xa, ya = PROX * c1, PROX * s1
    xb, yb = D + PROX * c2, PROX * s2
    hx, hy = xb - xa, yb - ya
    hm = np.sqrt(hx * hx + hy * hy)
    cb = -(DIST * DIST - DIST * DIST - hm * hm) / (2 * DIST * hm)
    h1x, h1y = DIST * cb * hx / hm, DIST * cb * hy / hm
    h1m = np.sqrt(h1x * h1x + h1y * h1y)
    sb = np.sqrt(1 - cb * cb)
    lx, ly = -DIST * sb * h1y / h1m, DIST * sb * h1x / h1m
    xp, yp = xa + h1x + lx, ya + h1y + ly
    phi1 = np.arccos((xp - PROX * c1) / DIST)
    phi2 = np.arccos((xp - D - PROX * c2) / DIST)
    c11, s11, c22, s22 = np.cos(phi1), np.sin(phi1), np.cos(phi2), np.sin(phi2)
    dn = DIST * (c11 * s22 - c22 * s11)
    eta = (-DIST * c11 * s22 + DIST * c22 * s11 - c1 * PROX * s22 + c22 * PROX * s1) / dn
    nu = PROX * (c2 * s22 - c22 * s2) / dn
    jt11 = -DIST * eta * s11 - DIST * s11 - PROX * s1
    jt12 = DIST * c11 * eta + DIST * c11 + c1 * PROX
    jt = np.stack([np.stack([jt11, jt12], -1), np.stack([-DIST * s11 * nu, DIST * c11 * nu], -1)], -2)
    return np.stack([xp, yp], -1), jt


def _haply_poses(n: int, seed: int):
    """Joint angles (k, 2) of well-conditioned '+-' poses with the end-effector above both elbows.

    hAPI takes each distal link's angle as phi = acos(...) in [0, pi] (Pantograph.java:102-103), so
    its JT holds only where both distal links point away from the motors (docs/devices.md)."""
    rng = np.random.default_rng(seed)
    x = np.stack([rng.uniform(-0.08, 0.08, 8 * n), rng.uniform(0.06, 0.14, 8 * n)], -1)
    q, ok = HAPLY.inverse(x)
    elbows = HAPLY.elbows(q[ok])
    up = np.all(elbows[..., 1] < x[ok][:, None, 1], axis=-1)
    cond = np.linalg.cond(HAPLY.jacobian(q[ok], x[ok]))
    keep = np.flatnonzero(ok)[up & (cond < 20)][:n]
    assert len(keep) == n
    return q[keep], x[keep]


def test_haply_forward_kinematics_and_jacobian_are_hapis():
    """hAPI's forward kinematics and JT (Pantograph.java) at the same joint angles: the position is
    ours shifted by d / 2 (motor 1 at the hAPI origin), and JT is our J transposed. hAPI's
    phi = acos(...) loses accuracy as sqrt(eps) where its argument nears 1 (distal link near
    horizontal): poses with condition number below 20 keep it within 1e-7 of the link scale."""
    q, x = _haply_poses(200, seed=5)
    pos, jt = _hapi_forward(q[:, 0], q[:, 1])
    assert np.max(np.abs(pos - (x + np.array([D / 2, 0.0])))) <= 64 * EPS
    jac = HAPLY.jacobian(q, x)
    assert np.max(np.abs(jt - np.swapaxes(jac, -1, -2))) <= 1e-7 * DIST


def test_haply_isotropic_force_from_hapis_jacobian_and_the_firmware_clamp():
    """With hAPI's own JT and the firmware's MAX_TORQUE = 0.123 N m on each motor
    (Haply_M0_Firmware_V0_3.h:43), the largest force held in every direction is
    min_u 0.123 / |JT[u, :]| (paper 000 eq. 8); the preset gives the same."""
    q, x = _haply_poses(50, seed=6)
    _, jt = _hapi_forward(q[:, 0], q[:, 1])
    by_source = np.min(0.123 / np.linalg.norm(jt, axis=-1), axis=-1)
    got = isotropic_force(HAPLY.jacobian(q, x), torque_limits=HAPLY.torque_limits())
    assert np.allclose(got, by_source, rtol=1e-6, atol=0.0)      # JT agrees to 1e-7 (test above)
    assert np.allclose(HAPLY.torque_limits(), [0.123, 0.123], rtol=0.0, atol=0.0)


def test_haply_start_pose_is_hapis():
    """The gen 3 start angles of hAPI's demo (maze_study_demo.pde:130-131: 168 deg, 12 deg) put the
    end-effector on the symmetry axis, 70 sin 12 + sqrt(90^2 - (19 + 70 cos 12)^2) = 35.74 mm out."""
    q = np.array([168.0, 12.0]) * DEG
    x, ok = HAPLY.forward(q)
    by_hand = 0.070 * np.sin(12 * DEG) + np.sqrt(0.090 ** 2 - (0.019 + 0.070 * np.cos(12 * DEG)) ** 2)
    assert bool(ok) and np.allclose(x, [0.0, by_hand], rtol=0.0, atol=16 * EPS)
    assert by_hand == pytest.approx(0.03574, abs=1e-5)


# -- Novint Falcon: maxima decided by the delta's singular loci ----------------------------------------
def test_falcon_condition_number_is_unbounded_at_a_direct_singularity_and_the_forces_are_not():
    """With the estimated limits (knee bend 10-170 deg, bars within 50 deg of square) no knee reaches
    its fold, so the anisotropic and isotropic force maxima over the preset's map are finite; but the
    feasible set crosses the surface where the bars are coplanar (direct singularity), so the
    condition number's is not (3873 +- 3551 was a grid figure)."""
    preset = load_preset("novint_falcon")
    names = ["condition_number", "anisotropic_force", "isotropic_force"]
    out = unbounded_suprema(preset.mechanism, preset.grid, names)
    assert sorted(out) == ["condition_number"]
    opened = preset.mechanism.replace(knee_min=1e-6, knee_max=np.pi)
    out = unbounded_suprema(opened, preset.grid, names)
    # Knees allowed to stretch: one arm's column of J -> 0 (anisotropic force unbounded), and on the
    # axis all three at once at z = 183 mm, inside the map (isotropic force unbounded).
    assert sorted(out) == sorted(names)
    assert np.any(np.abs(out["isotropic_force"][:, 2] - 0.1832) < 1e-3)


def test_joint_resolutions_follow_from_each_sources_encoder():
    """Joint-side counts from each source's encoder figure (re-typed here from the source, not the preset)."""
    from metrics.resolution import mechanism_steps

    deg = np.pi / 180
    # mahilab/Phantom README: HEDM-5500, 1024 cpr, X4 quadrature -> 4096 counts per motor turn, through Eta.
    phantom = mechanism_steps(load_preset("phantom_premium_15").mechanism)
    assert phantom == pytest.approx([2 * np.pi / (4096 * e) for e in (13.3, 11.2, 11.2)], rel=1e-15)
    # libnifalcon FalconKinematic::getTheta: degrees of arm per encoder count.
    per_count = (0.01425 * np.pi / (320 * 4)) / (np.pi * 0.110 / 360.0)
    assert mechanism_steps(load_preset("novint_falcon").mechanism) == pytest.approx([per_count * deg] * 3, rel=1e-12)
    # hAPI maze demo (hardware version 3): 4880 counts per turn on the link angles.
    assert mechanism_steps(load_preset("haply_2diy").mechanism) == pytest.approx([2 * np.pi / 4880] * 2, rel=1e-12)
    # No public encoder data: no resolution at all, rather than another device's.
    for key in ("phantom_omni", "woodenhaptics", "fivebar_singh"):
        assert mechanism_steps(load_preset(key).mechanism) is None


def test_woodenhaptics_gravity_is_the_sources_two_body_potential():
    """The source's gravity model (CWoodenDevice.cpp:97 masses and centres, :870-878) is the potential
    ``V = g (mB Lb_cm cos tB + mC (Lb cos tB - Lc_cm sin(tB + tC)))`` of bodies B and C; the preset's
    other bodies add none (the drum and the turret keep their heights) but the 1 g placeholder
    follower at the crank end. Without it, ``dV/dq`` is the source's to rounding; with it, within 0.5 %.
    """
    mb, mc, lb_cm, lc_cm, g = 0.170, 0.110, 0.051, 0.091, 9.81          # :97, g_constant 9.81
    tb, tca = np.meshgrid(np.linspace(10, 80, 8) * DEG, np.linspace(-20, 60, 9) * DEG)
    tb, tca = tb.ravel(), tca.ravel()
    q = np.stack([np.zeros_like(tb), np.pi / 2 - tb, np.pi / 2 - tca], -1)
    # dV/dq2 = -dV/dtB, dV/dq3 = -dV/dtCa (q2 = 90 deg - tB, q3 = 90 deg - (tB + tC)).
    source = np.stack([np.zeros_like(tb), g * np.sin(tb) * (mb * lb_cm + mc * LB), g * mc * lc_cm * np.cos(tca)], -1)
    masses = list(WOODY.params.link_masses)
    masses[1] = 1e-300                                                   # the placeholder follower, off
    bare = WOODY.replace(link_masses=tuple(masses))
    gravity = (0.0, 0.0, -g)
    np.testing.assert_allclose(bare.gravity_torque(q, gravity), source, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(WOODY.gravity_torque(q, gravity), source, rtol=5e-3, atol=3e-4)
