"""Delta positioner (Novint Falcon defaults): IK against libnifalcon's own formulas, a symmetric pose
checked by hand, the Jacobian against central differences of FK, FK(IK(x)) round trips, masks
(unreachable, non-assembling, limits, non-finite), validation, and the preset against the
figures of its sources (``docs/devices.md``).

Headless: numpy only. Fixed seeds.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from kinematics import Delta, DeltaParams
from kinematics.delta import FK_RTOL
from resources import load_preset

EPS = np.finfo(float).eps
DEG = np.pi / 180.0
FALCON = Delta()


def _samples(mech: Delta, count: int, seed: int) -> np.ndarray:
    """Feasible, well-conditioned platform points of ``mech`` (count, 3) around the workspace centre."""
    rng = np.random.default_rng(seed)
    x = np.array([0.0, 0.0, 0.11]) + rng.uniform(-0.05, 0.05, (20 * count, 3))
    q, ok = mech.inverse(x)
    keep = ok.copy()
    keep[ok] = mech.feasible(q[ok], x[ok])
    sv = np.linalg.svd(mech.jacobian(q[keep], x[keep]) / mech.size(), compute_uv=False)
    good = np.flatnonzero(keep)[sv[:, 0] / sv[:, -1] < 20]
    assert good.size >= count
    return x[good[:count]]


def _libnifalcon_ik(x: np.ndarray, p: DeltaParams) -> tuple[np.ndarray, np.ndarray]:
    """libnifalcon's IK (src/kinematic/FalconKinematicStamper.cpp:28-93) transcribed term by term,
    with a rounding-error bound for each angle (rad): arm angles (k, 3) and bounds (k, 3)."""
    a, b, c, d, e, f, r, s = (p.upper_arm, p.parallelogram, p.platform_offset_u, p.platform_joint_offset,
                              p.knee_offset, p.platform_offset_v, p.base_radius, p.base_offset_v)
    size = FALCON.size()
    out, bound = np.empty_like(x), np.empty_like(x)
    for i, phy in enumerate(np.array([np.pi / 2, -np.pi / 6, -5 * np.pi / 6]) + p.arm_offset_angle):
        pu = math.cos(phy) * x[:, 0] + math.sin(phy) * x[:, 1] - r
        pv = -math.sin(phy) * x[:, 0] + math.cos(phy) * x[:, 1] - s
        pw = x[:, 2]
        t3 = np.arccos((pv + f) / b)
        sn = np.sin(t3)
        common = (pw * pw + pu * pu + 2 * c * pu + a * a + c * c - d * d - e * e - b * b * sn * sn
                  - 2 * b * e * sn - 2 * b * d * sn - 2 * d * e)
        l0 = common - 2 * a * pu - 2 * a * c
        l1 = -4 * a * pw
        l2 = common + 2 * a * pu + 2 * a * c
        disc = l1 * l1 - 4 * l0 * l2
        t = (-l1 - np.sqrt(disc)) / (2 * l2)
        out[:, i] = 2 * np.arctan(t)
        # Each l is a sum of ~15 products of lengths below S: error ~ 15 eps S^2 = delta. The root
        # moves by delta (1 + (|l1| + 2|l0| + 2|l2|) / sqrt(disc) + 2|t|) / |2 l2|, the angle by
        # 2 / (1 + t^2) times that; the acos of theta3 adds eps / sin(theta3) through sin(theta3).
        delta = 15 * EPS * size ** 2
        dt = delta * (1 + (np.abs(l1) + 2 * np.abs(l0) + 2 * np.abs(l2)) / np.sqrt(disc) + 2 * np.abs(t))
        dt = dt / np.abs(2 * l2) + 4 * EPS * b * b * size / np.abs(l2) / sn
        bound[:, i] = 2 * dt / (1 + t * t)
    return out, bound


# -- inverse kinematics against the source ----------------------------------------------------
def test_inverse_kinematics_reproduces_libnifalcons_formulas():
    x = _samples(FALCON, 200, seed=1)
    q, ok = FALCON.inverse(x)
    ref, bound = _libnifalcon_ik(x, FALCON.params)
    assert ok.all()
    # Our closed form (atan2 - acos) rounds to a few eps / sin(acos) rad; 100 covers both constants.
    assert np.all(np.abs(q - ref) <= 100 * bound + 100 * EPS), np.max(np.abs(q - ref) / bound)


def test_symmetric_pose_on_the_axis_by_hand():
    """On the device axis every leg sees the same geometry: all arm angles equal, and J maps equal
    arm rates to motion along z only, at the rate dz/dq of the planar closure (derived by hand)."""
    p = FALCON.params
    z = 0.11
    x = np.array([0.0, 0.0, z])
    q, ok = FALCON.inverse(x)
    assert ok
    # By hand: P_u + c = c - r, P_v + f = f - s = b cos(theta3); the forearm's reach in the u-w plane
    # is L = D + b sin(theta3); the knee is the circle-circle intersection (outward root).
    cos3 = (p.platform_offset_v - p.base_offset_v) / p.parallelogram
    reach = p.knee_offset + p.platform_joint_offset + p.parallelogram * math.sqrt(1 - cos3 ** 2)
    qu = p.platform_offset_u - p.base_radius
    rho = math.hypot(qu, z)
    q_hand = math.atan2(z, qu) - math.acos((rho ** 2 + p.upper_arm ** 2 - reach ** 2) / (2 * p.upper_arm * rho))
    # Error of each form: a few eps / sin(acos argument) (the argument is far from +-1 here).
    np.testing.assert_allclose(q, q_hand, rtol=0, atol=1e3 * EPS)
    assert math.degrees(q_hand) == pytest.approx(16.188, abs=1e-3)    # libnifalcon's IK gives 16.18796 deg
    # Closure (qu - a cos q)^2 + (z - a sin q)^2 = L^2 differentiated along z with equal arms:
    a = p.upper_arm
    dz = a * math.cos(q_hand) - (qu - a * math.cos(q_hand)) * a * math.sin(q_hand) / (z - a * math.sin(q_hand))
    jac = FALCON.jacobian(q, x)
    rate = jac @ np.ones(3)
    np.testing.assert_allclose(rate, [0.0, 0.0, dz], rtol=0, atol=1e3 * EPS * abs(dz))
    # The three columns are the one column turned by the legs' azimuths (120 deg apart) about z.
    turn = np.array([[math.cos(2 * np.pi / 3), -math.sin(2 * np.pi / 3), 0],
                     [math.sin(2 * np.pi / 3), math.cos(2 * np.pi / 3), 0], [0, 0, 1]])
    np.testing.assert_allclose(turn @ jac[:, 0], jac[:, 2], rtol=0, atol=1e3 * EPS * np.abs(jac).max())


# -- Jacobian ----------------------------------------------------------------------------------
def test_jacobian_matches_central_differences_of_forward_kinematics():
    # Step h = eps^(1/3) rad: truncation h^2/6 |x'''| ~ eps^(2/3) S (the kinematics curve on the scale
    # of 1 rad with the points kept at condition < 20) and rounding eps S / h = eps^(2/3) S; FK itself
    # is accurate to FK_RTOL S, which divides by h too. 100 covers the constants.
    x = _samples(FALCON, 100, seed=2)
    q, _ = FALCON.inverse(x)
    jac = FALCON.jacobian(q, x)
    h = EPS ** (1 / 3)
    cols = []
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = h
        xp, okp = FALCON.forward(q + dq)
        xm, okm = FALCON.forward(q - dq)
        assert okp.all() and okm.all()
        cols.append((xp - xm) / (2 * h))
    numeric = np.stack(cols, -1)
    size = FALCON.size()
    tol = 100 * (EPS ** (2 / 3) + FK_RTOL / h) * size
    assert np.max(np.abs(numeric - jac)) <= tol, np.max(np.abs(numeric - jac)) / tol


def test_jacobian_without_x_equals_with_x():
    x = _samples(FALCON, 10, seed=3)
    q, _ = FALCON.inverse(x)
    np.testing.assert_allclose(FALCON.jacobian(q), FALCON.jacobian(q, x), rtol=0,
                               atol=1e3 * FK_RTOL * np.abs(FALCON.jacobian(q, x)).max())


# -- round trips ---------------------------------------------------------------------------------
@pytest.mark.parametrize("params", [DeltaParams(), DeltaParams(knee_offset=0.0, platform_joint_offset=0.0),
                                    DeltaParams(knee_offset=0.03, platform_joint_offset=0.03)],
                         ids=["falcon", "sphere-delta", "large-offsets"])
def test_forward_of_inverse_is_the_point(params):
    """FK stops at FK_RTOL S on the residuals; the well-conditioned samples (condition < 20) turn
    that into at most 20 FK_RTOL S in position, and IK's rounding adds a few eps S."""
    mech = Delta(params)
    x = _samples(mech, 100, seed=4)
    q, ok = mech.inverse(x)
    back, fok = mech.forward(q)
    assert ok.all() and fok.all()
    assert np.max(np.abs(back - x)) <= 20 * (FK_RTOL + 10 * EPS) * mech.size()
    again, _ = mech.inverse(back)
    np.testing.assert_allclose(again, q, rtol=0, atol=1e-9)


def test_a_batch_equals_one_point_at_a_time():
    x = _samples(FALCON, 6, seed=5).reshape(2, 3, 3)
    q, ok = FALCON.inverse(x)
    back, fok = FALCON.forward(q)
    assert q.shape == (2, 3, 3) and ok.shape == (2, 3) and fok.all()
    for i in range(2):
        for j in range(3):
            np.testing.assert_allclose(FALCON.forward(q[i, j])[0], back[i, j], rtol=0, atol=1e-15)


# -- masks ---------------------------------------------------------------------------------------
def test_unreachable_points_and_non_finite_input_are_masked():
    pts = np.array([[0.0, 0.0, 0.11], [0.0, 0.0, 1.0], [0.5, 0.0, 0.1], [np.nan, 0, 0.1], [np.inf] * 3])
    q, ok = FALCON.inverse(pts)
    assert ok.tolist() == [True, False, False, False, False]
    assert np.all(np.isnan(q[1:]))
    back, fok = FALCON.forward(np.array([[np.nan] * 3, [np.inf] * 3]))
    assert not fok.any() and np.all(np.isnan(back))
    assert not FALCON.feasible(np.full((2, 3), np.nan)).any()


def test_forward_masks_arms_that_cannot_assemble():
    # Short bars: the three ring points are farther apart than a sphere of radius b spans.
    short = Delta(parallelogram=0.05)
    x, ok = short.forward(np.zeros((1, 3)))
    assert not ok.any() and np.all(np.isnan(x))
    # The same arm angles assemble with the Falcon's bars; a batch keeps the good and masks the bad.
    x, ok = FALCON.forward(np.zeros((1, 3)))
    assert ok.all()
    # A batch keeps the good and masks the bad: with the short bars, arms raised to 86 deg bring the
    # knees close enough together to assemble, arms flat (0 deg) do not.
    x, ok = short.forward(np.array([[1.5, 1.5, 1.5], [0.0, 0.0, 0.0]]))
    assert ok.tolist() == [True, False] and np.all(np.isnan(x[1])) and x[0, 2] > 0


def test_feasibility_limits_are_enforced():
    x = np.array([0.0, 0.0, 0.11])
    q, _ = FALCON.inverse(x)
    assert FALCON.feasible(q, x)
    assert not FALCON.replace(arm_upper=float(q[0]) - 1e-6).feasible(q, x)
    assert not FALCON.replace(arm_lower=float(q[0]) + 1e-6).feasible(q, x)
    bend, theta3 = FALCON.leg_angles(q, x)
    assert not FALCON.replace(knee_max=float(bend[0]) - 1e-6).feasible(q, x)
    assert not FALCON.replace(bar_limit=abs(float(theta3[0]) - np.pi / 2) - 1e-6).feasible(q, x)


def test_singularity_codes_at_a_folded_arm():
    """An arm folded so its knee moves along its bar (B_ii = 0) is an inverse singularity."""
    x = _samples(FALCON, 5, seed=6)
    q, _ = FALCON.inverse(x)
    assert not FALCON.singularity(q, x).any()
    # Find the arm angle where n . dk/dq changes sign along arm 1 (platform point from FK).
    grid = np.linspace(-np.pi, np.pi, 2001)
    qs = np.stack([grid, np.full_like(grid, 0.3), np.full_like(grid, 0.3)], -1)
    xs, ok = FALCON.forward(qs)
    _, b_diag = FALCON._velocity_matrices(qs[ok], xs[ok])
    flips = np.flatnonzero(np.diff(np.sign(b_diag[:, 0])) != 0)
    assert flips.size
    lo, hi = qs[ok][flips[0], 0], qs[ok][flips[0] + 1, 0]
    for _ in range(60):                     # bisection to the sign change
        mid = 0.5 * (lo + hi)
        xm, _ = FALCON.forward([mid, 0.3, 0.3])
        _, bm = FALCON._velocity_matrices(np.array([mid, 0.3, 0.3]), xm)
        xl, _ = FALCON.forward([lo, 0.3, 0.3])
        _, bl = FALCON._velocity_matrices(np.array([lo, 0.3, 0.3]), xl)
        lo, hi = (mid, hi) if np.sign(bm[0]) == np.sign(bl[0]) else (lo, mid)
    qsing = np.array([0.5 * (lo + hi), 0.3, 0.3])
    assert FALCON.singular_legs(qsing).tolist() == [True, False, False]
    assert int(FALCON.singularity(qsing)) == 1


# -- validation -----------------------------------------------------------------------------------
@pytest.mark.parametrize("changes, match", [
    (dict(upper_arm=-0.01), "upper_arm"), (dict(knee_offset=-1e-3), "knee_offset"),
    (dict(arm_lower=1.0, arm_upper=0.5), "arm_lower"), (dict(base_radius=float("nan")), "base_radius"),
    (dict(motor_torques=(1.0, 0.0, 1.0)), "motor_torques"), (dict(bar_limit=2.0), "bar_limit"),
])
def test_invalid_parameters_name_the_argument(changes, match):
    with pytest.raises(ValueError, match=match):
        DeltaParams(**changes)


# -- the preset against its sources -----------------------------------------------------------------
def test_falcon_preset_against_its_sources():
    """libnifalcon: capstan ratio SMALL_ARM_DIAMETER / SHAFT_DIAMETER (FalconGeometry.h:21-22) and the
    torque its force scaling implies (0.4096 N m at the arm, our estimate). Novint's figures (third
    party): 4 in workspace, 2 lbf (8.9 N) maximum force. At the workspace centre the largest force the
    device holds in every direction (isotropic) must lie below 8.9 N and the largest in its best
    direction (anisotropic) above it, if the estimated torque is consistent with the published force."""
    from metrics import anisotropic_force, isotropic_force
    preset = load_preset("novint_falcon")
    mech = preset.mechanism
    np.testing.assert_allclose(mech.params.gear_ratios, 0.110 / 0.01425, rtol=1e-15)
    np.testing.assert_allclose(mech.torque_limits(), 0.4096, rtol=1e-3)      # motor_torques rounded to 4 digits
    x = np.array(preset.pose)
    q, ok = mech.inverse(x)
    jac = mech.jacobian(q, x)
    iso = float(isotropic_force(jac, torque_limits=mech.torque_limits()))
    aniso = float(anisotropic_force(jac, torque_limits=mech.torque_limits()))
    assert iso < 2 * 4.4482216152605 < aniso
    # The map box holds the whole estimated workspace: no feasible point on its faces.
    grid = preset.grid
    pts = grid.points(mech.task_names).reshape(-1, 3)
    qq, ok = mech.inverse(pts)
    feas = np.zeros(len(pts), bool)
    feas[ok] = mech.feasible(qq[ok], pts[ok])
    lo, hi = np.array(grid.lower), np.array(grid.upper)
    on_face = np.any(np.isclose(pts, lo) | np.isclose(pts, hi), axis=-1)
    assert feas.any() and not feas[on_face].any()


# -- singularity analysis ---------------------------------------------------------------------------
# A Falcon whose limits let the legs reach their inverse singularities (knee bend (0, pi], bars
# anywhere, arms almost all the way round): the loci are then inside its feasible set.
OPEN = FALCON.replace(knee_min=1e-6, knee_max=np.pi, bar_limit=np.pi / 2, arm_lower=-3.1, arm_upper=3.1)


def _fd_columns(mech: Delta, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dx/dq (k, 3, 3) by central differences of FK, step eps^(1/3) (rad), and where FK assembled
    at every step (k,)."""
    h = EPS ** (1 / 3)
    cols, ok = [], np.ones(len(q), bool)
    for i in range(3):
        dq = np.zeros(3)
        dq[i] = h
        xp, okp = mech.forward(q + dq)
        xm, okm = mech.forward(q - dq)
        ok &= okp & okm
        cols.append((xp - xm) / (2 * h))
    return np.stack(cols, -1), ok


def test_exactly_singular_poses_are_classed_singular_within_the_derived_tolerance():
    """Poses built on a locus in exact arithmetic (bend 0 or pi, or theta3 0 or pi) come back with
    ``|B_ii| / (|n_i| a)`` at or below ``singular_tolerances``: the bound holds for the rounding."""
    from kinematics.delta_loci import _place
    rng = np.random.default_rng(11)
    n, reached = 20000, 0
    for leg in range(3):
        arm = rng.uniform(-0.5, 1.5, n)
        bar = rng.uniform(0.6, np.pi - 0.6, n)
        for x in (_place(OPEN, leg, arm, 0.0, bar), _place(OPEN, leg, arm, np.pi, bar),
                  _place(OPEN, leg, arm, rng.uniform(0.3, 2.8, n), 0.0)):
            # The other legs must reach the point, and on the fold itself rounding puts many of the
            # points a few ulps outside the reach (cos theta3 = 1 + 1 ulp): keep the reachable ones.
            q, ok = OPEN.inverse(x)
            assert ok.any() or np.allclose(OPEN._reach_terms(x)[2][:, leg], 1.0, rtol=0.0, atol=4 * EPS)
            assert OPEN.singular_legs(q[ok], x[ok])[:, leg].all()
            reached += ok.sum()
    assert reached >= 60
    # ... and regular poses are not: the tolerance is far below the ratio there.
    x = _samples(FALCON, 50, seed=12)
    q, _ = FALCON.inverse(x)
    assert not FALCON.singular_legs(q, x).any()
    assert np.all(FALCON.singular_tolerances(x) < 1e-6)


def test_inverse_loci_are_one_leg_just_inside_its_fold_by_central_differences():
    """At each feasible "inverse" point one column of dx/dq (central differences of FK) is ~EDGE
    times the others', and the analytic J agrees; brute force over the leg angles says which leg."""
    from kinematics.delta_loci import EDGE
    x = OPEN.singular_loci()["inverse"]
    q, ok = OPEN.inverse(x)
    keep = ok.copy()
    keep[ok] = OPEN.feasible(q[ok], x[ok])
    x, q = x[keep][::7], q[keep][::7]
    assert len(x) >= 50
    bend, theta3 = OPEN.leg_angles(q, x)
    near = np.minimum(np.minimum(bend, np.pi - bend), np.minimum(theta3, np.pi - theta3))
    leg = np.argmin(near, axis=-1)
    # The point was placed EDGE inside one fold; rounding moves the angle by ~1e-7 (singular_tolerances).
    # Points placed at the ends of the open limit ranges (bend pi, say) sit on a second fold too.
    nearest = near[np.arange(len(x)), leg]
    assert np.all(nearest <= 1.05 * EDGE)
    assert np.mean(np.abs(nearest - EDGE) <= 0.05 * EDGE) > 0.9
    # FK finds the front assembly only (``forward``): keep the points it reproduces.
    xf, okf = OPEN.forward(q)
    same = okf & (np.linalg.norm(np.where(okf[:, None], xf, 0.0) - x, axis=-1) <= 1e-9 * OPEN.size())
    fd, okd = _fd_columns(OPEN, q)
    same &= okd
    # ... and those away from a direct singularity (bars far from coplanar), where FK curves on the
    # scale S: near one it folds and the differences below lose their eps^(2/3) accuracy.
    a_mat, _ = OPEN._velocity_matrices(q, x)
    sv = np.linalg.svd(a_mat, compute_uv=False)
    same &= sv[:, -1] >= 0.1 * sv[:, 0]
    assert same.sum() >= 30
    x, q, fd, leg = x[same], q[same], fd[same], leg[same]
    jac = OPEN.jacobian(q, x)
    norms = np.linalg.norm(fd, axis=-2)                                   # (k, 3)
    small = norms[np.arange(len(x)), leg]
    # |dx/dq_i| ~ rho sin(bend) ~ S EDGE at a fold, the other columns ~ S: ratio ~ EDGE, well below 1e-3.
    others = np.sort(norms, axis=-1)[:, 1]
    assert np.all(small <= 1e-3 * others)
    # FK is smooth at an inverse singularity (it folds only at direct ones), so the central
    # differences are off by (h^2 / 6) |d3x/dq3| ~ eps^(2/3) times the columns' scale; 1e3 covers
    # the curvature constants (the contract test's bound for regular poses).
    err = np.linalg.norm(jac - fd, axis=-2)
    assert np.all(err <= 1e3 * EPS ** (2 / 3) * norms.max(axis=-1, keepdims=True))
    # The analytic column of the singular leg is as small as the differenced one.
    assert np.all(np.linalg.norm(jac, axis=-2)[np.arange(len(x)), leg] <= 1e-3 * others)


def test_all_inverse_loci_on_the_axis_are_just_inside_the_reach_found_by_bisection():
    """The all-inverse points on the z axis (all three knees stretched, or folded, by symmetry) lie
    just inside the end of the axis' reach, found independently by bisecting ``inverse``'s
    reachable flag along the axis, and every leg's ``B_ii`` is as small as the law of sines says."""
    from kinematics.delta_loci import EDGE
    pts = OPEN.singular_loci()["all_inverse"]
    on_axis = pts[np.hypot(pts[:, 0], pts[:, 1]) < 1e-9 * OPEN.size()]
    assert len(on_axis) >= 2

    def reachable(z):
        return bool(OPEN.inverse(np.array([0.0, 0.0, z]))[1])

    for z_star in on_axis[:, 2]:
        assert reachable(z_star)
        # The nearer end of the reach: the knee is at the fold within a millimetre of z_star.
        out = next(z_star + d for d in (1e-3, -1e-3) if not reachable(z_star + d))
        inside, outside = z_star, out
        for _ in range(80):
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if reachable(mid) else (inside, mid)
        # k = 1 - EDGE^2 / 2 is 5e-11 from the fold; k changes by ~1/L per metre along the axis, so the
        # point is ~L EDGE^2 / 2 ~ 1e-11 m inside: between 0 and 1e-9 S (3e-10 m) of the end.
        assert 0.0 < abs(outside - z_star) <= 1e-9 * OPEN.size()
        x = np.array([0.0, 0.0, z_star])
        q, _ = OPEN.inverse(x)
        _, ratio, _ = OPEN._leg_ratios(q, x)
        # B_ii / (|n_i| a) = sin(theta3) sin(bend), and the bend is rho / L times the arm's angle
        # EDGE from the platform direction (law of sines): J -> 0 (or 0 / 0 where the bars are also
        # near coplanar).
        _, _, _, rho, reach, _ = OPEN._reach_terms(x)
        assert np.all(ratio <= 1.01 * EDGE * rho / reach)
        assert np.all(ratio >= 0.5 * EDGE * rho / reach * np.sqrt(1 - OPEN._reach_terms(x)[2] ** 2))


def test_direct_loci_are_on_a_sign_change_of_det_a_found_by_brute_force():
    """The Falcon preset's own map (brute force over its grid) holds feasible points on both sides of
    ``det A = 0``, so the feasible set crosses a direct singularity; ``singular_loci`` finds feasible
    points on it, each classed direct, with J's largest singular value unbounded in truth (> 1e5 S)."""
    preset = load_preset("novint_falcon")
    mech, grid = preset.mechanism, preset.grid
    axes = [np.linspace(lo, hi, n) for lo, hi, n in zip(grid.lower, grid.upper, grid.resolution)]
    x = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    q, ok = mech.inverse(x)
    feas = ok.copy()
    feas[ok] = mech.feasible(q[ok], x[ok])
    a_mat, _ = mech._velocity_matrices(q[feas], x[feas])
    det = np.linalg.det(a_mat)
    assert (det > 0).any() and (det < 0).any()
    pts = mech.singular_loci()["direct"]
    qd, okd = mech.inverse(pts)
    assert okd.all()
    keep = mech.feasible(qd, pts)
    assert keep.sum() >= 3
    assert np.all(mech.singularity(qd[keep], pts[keep]) == 2)
    a_mat, _ = mech._velocity_matrices(qd[keep], pts[keep])
    sv = np.linalg.svd(a_mat, compute_uv=False)
    assert np.all(sv[:, -1] <= 1e-9 * sv[:, 0])                      # bisected to rounding


def test_singular_loci_are_computed_once_and_returned_as_copies():
    first = FALCON.singular_loci()
    first["inverse"][:] = 0.0
    again = Delta().singular_loci()
    assert np.abs(again["inverse"]).max() > 0
