"""The mechanism contract (``kinematics.contract.Mechanism``), checked for every registered kind and preset.

Adding a mechanism means one module in ``kinematics/``, one entry in ``kinematics.registry``,
one preset, and passing this file. Everything here goes through the contract only: no test
asks a model for anything the protocol does not promise.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from kinematics.registry import MECHANISMS, kind_of, mechanism_class
from resources import list_presets, load_preset

EPS = np.finfo(float).eps


def _cases():
    cases = []
    presets = {key: load_preset(key) for key in list_presets()}
    for kind, cls in MECHANISMS.items():
        # A kind's default model, sampled over the first preset of that kind's domain.
        preset = next(p for p in presets.values() if p.kind == kind)
        cases.append(pytest.param(cls(), preset, id=f"default-{kind}"))
    for key, preset in presets.items():
        cases.append(pytest.param(preset.mechanism, preset, id=key))
    return cases


CASES = _cases()


def _device_scale(mech, x) -> float:
    """Size of the device (m): the largest distance of a link point from the origin at poses ``x``."""
    q, _ = mech.inverse(x)
    pts = mech.link_points(q)
    return float(np.nanmax(np.linalg.norm(pts, axis=-1)))


def _samples(mech, preset, count=400, seed=0, *, orientation=0.0):
    """Random task points (k, m) over the preset's map box, the fixed position coordinates shaken
    by a tenth of the box, orientation coordinates uniform in +-``orientation`` rad; only the
    reachable, feasible ones."""
    rng = np.random.default_rng(seed)
    grid = preset.grid
    fixed = dict(grid.fixed)
    spans = [hi - lo for lo, hi in zip(grid.lower, grid.upper)]
    shake = 0.1 * max(spans)
    cols = []
    for name, unit in zip(mech.task_names, mech.task_units):
        if name in grid.axes:
            k = grid.axes.index(name)
            cols.append(rng.uniform(grid.lower[k], grid.upper[k], count))
        elif unit == "rad":
            cols.append(fixed.get(name, 0.0) + rng.uniform(-orientation, orientation, count))
        else:
            cols.append(fixed.get(name, 0.0) + rng.uniform(-shake, shake, count))
    x = np.stack(cols, -1)
    q, ok = mech.inverse(x)
    good = ok.copy()
    good[ok] = mech.feasible(q[ok], x[ok])
    return x[good]


def _regular(mech, x, bound=1e3):
    """The points of ``x`` where the task-scaled J is finite and its condition number below ``bound``,
    with the scaled condition number of each."""
    q, _ = mech.inverse(x)
    jac = mech.jacobian(q, x)
    scaled = jac / _task_scale(mech, _device_scale(mech, x))[:, None]
    finite = np.all(np.isfinite(scaled), axis=(-2, -1))
    cond = np.full(len(x), np.inf)
    sv = np.linalg.svd(scaled[finite], compute_uv=False)
    cond[finite] = sv[:, 0] / sv[:, -1]
    keep = cond < bound
    return x[keep], cond[keep]


def _task_scale(mech, scale):
    """Per task coordinate: the device scale (m) for lengths, 1 for angles (rad), shape (m,)."""
    return np.array([scale if u == "m" else 1.0 for u in mech.task_units])


def _joint_scale(mech, scale):
    return np.array([scale if u == "m" else 1.0 for u in mech.joint_units])


# -- declared structure -----------------------------------------------------------------------
@pytest.mark.parametrize("mech, preset", CASES)
def test_declared_names_and_units(mech, preset):
    n, m = mech.n_joints, mech.task_dim
    assert len(mech.joint_names) == n and len(mech.task_names) == m
    assert len(mech.task_units) == m and set(mech.task_units) <= {"m", "rad"}
    assert len(mech.joint_units) == n and set(mech.joint_units) <= {"m", "rad"}
    assert mech.has_orientation == ("rad" in mech.task_units)
    assert mech.is_redundant == (n > m)
    if mech.has_orientation:
        assert np.isfinite(mech.characteristic_length) and mech.characteristic_length > 0
    else:
        assert mech.characteristic_length is None
    t = mech.torque_limits()
    assert t.shape == (n,) and np.all(np.isfinite(t) & (t > 0))
    classes = mech.singularity_classes
    assert isinstance(classes, tuple) and all(isinstance(c, str) for c in classes)
    assert mechanism_class(kind_of(mech)) is type(mech)


@pytest.mark.parametrize("mech, preset", CASES)
def test_singular_loci_are_task_points(mech, preset):
    for name, points in mech.singular_loci().items():
        assert isinstance(name, str)
        assert points.ndim == 2 and points.shape[1] == mech.task_dim


# -- derivatives ------------------------------------------------------------------------------
# Central differences with step h (m for lengths, rad for angles): truncation error
# h^2 / 6 |f'''| and rounding error ~ eps |f| / h. On a device of size S whose kinematics
# curve on the scale S, |f'''| ~ |f'| / S^2 and |f| ~ S |f'|, so with h = eps^(1/3) S both are
# ~ eps^(2/3) |f'| (relative). Near a singularity the kinematics curve on the scale of the
# distance to it, about S / cond (cond: the condition number of the task-scaled J), so the
# truncation error grows to eps^(2/3) cond^2; the factor 1e3 covers the curvature constants
# (points are kept where cond is below 1e3).
# Orientation coordinates are held at 0, where their rates are the angular-velocity (twist)
# components J maps to (the left Jacobian of the rotation vector, or of the tilt, is I there).
@pytest.mark.parametrize("mech, preset", CASES)
def test_jacobian_inverts_central_differences_of_the_inverse_kinematics(mech, preset):
    x = _samples(mech, preset, 200, seed=1)
    x, cond = _regular(mech, x)
    assert len(x) >= 10
    scale = _device_scale(mech, x)
    task = _task_scale(mech, scale)
    steps = EPS ** (1 / 3) * task
    q, _ = mech.inverse(x)
    jac = mech.jacobian(q, x)
    cols = []
    for i, h in enumerate(steps):
        dx = np.zeros(mech.task_dim)
        dx[i] = h
        qp, okp = mech.inverse(x + dx)
        qm, okm = mech.inverse(x - dx)
        assert okp.all() and okm.all()
        cols.append((qp - qm) / (2 * h))
    dq_dx = np.stack(cols, -1)                                   # (k, n, m)
    # Dimensionless: scale task rows and joint columns to the device size.
    identity = (jac / task[:, None]) @ (dq_dx * task[None, :])
    # The inverse kinematics is smooth at a direct singularity but has a square-root fold at an
    # inverse (stretched or folded leg) one: at a distance d from it, q ~ sqrt(d / S), the scaled
    # condition number is cond ~ sqrt(S / d) / 2, and the central-difference error of the product
    # above is (h / d)^2 / 8 = 2 eps^(2/3) cond^4 (the haply_2diy preset samples a point at
    # cond ~ 30 that shows it); that term is added with its constant 2 taken 8 times over.
    tol = EPS ** (2 / 3) * (1e3 * cond ** 2 + 16 * cond ** 4)
    err = np.max(np.abs(identity - np.eye(mech.task_dim)), axis=(-2, -1))
    assert np.all(err <= tol), (err / tol).max()


@pytest.mark.parametrize("mech, preset", [c for c in CASES if not c.values[0].is_redundant])
def test_jacobian_matches_central_differences_of_the_forward_kinematics(mech, preset):
    x = _samples(mech, preset, 200, seed=2)
    x, cond = _regular(mech, x)
    assert len(x) >= 10
    scale = _device_scale(mech, x)
    task, joint = _task_scale(mech, scale), _joint_scale(mech, scale)
    q, _ = mech.inverse(x)
    jac = mech.jacobian(q, x)
    cols = []
    for j, h in enumerate(EPS ** (1 / 3) * joint):
        dq = np.zeros(mech.n_joints)
        dq[j] = h
        xp, okp = mech.forward(q + dq)
        xm, okm = mech.forward(q - dq)
        assert okp.all() and okm.all()
        cols.append((xp - xm) / (2 * h))
    numeric = np.stack(cols, -1)
    scaled = jac * joint[None, :] / task[:, None]
    err = np.max(np.abs(numeric * joint[None, :] / task[:, None] - scaled), axis=(-2, -1))
    size = np.max(np.abs(scaled), axis=(-2, -1))
    assert np.all(err <= 1e3 * EPS ** (2 / 3) * cond ** 2 * size), err.max()


# -- round trips and batches ------------------------------------------------------------------
@pytest.mark.parametrize("mech, preset", CASES)
def test_forward_of_inverse_is_the_point(mech, preset):
    x = _samples(mech, preset, 200, seed=3, orientation=0.2)
    assert len(x) >= 10
    q, ok = mech.inverse(x)
    assert ok.all()
    back, ok = mech.forward(q)
    assert ok.all()
    scale = _device_scale(mech, x)
    # FK and IK each round to a few ulps of the device size; Newton (Stewart) stops at 16 eps S.
    # Near a fold the inverse amplifies that by the condition number, hence the keep bound below.
    x, cond = _regular(mech, x)
    q, _ = mech.inverse(x)
    back, _ = mech.forward(q)
    err = np.max(np.abs(back - x) / _task_scale(mech, scale), axis=-1)
    assert np.all(err <= 1e3 * EPS * cond), err.max()


@pytest.mark.parametrize("mech, preset", CASES)
def test_a_batch_equals_one_point_at_a_time(mech, preset):
    x = _samples(mech, preset, 60, seed=4, orientation=0.2)[:12]
    x = np.concatenate([x, np.full((1, mech.task_dim), np.nan)])
    q, ok = mech.inverse(x)
    jac = mech.jacobian(q, x)
    amap = mech.force_map(q, x)
    feas = np.zeros(len(x), bool)
    feas[ok] = mech.feasible(q[ok], x[ok])
    codes = mech.singularity(q, x)
    legs = mech.singular_legs(q, x)
    pts = mech.link_points(q)
    scale = _device_scale(mech, x[ok])
    for i in range(len(x)):
        qi, oki = mech.inverse(x[i])
        assert qi.shape == (mech.n_joints,) and oki.shape == () and bool(oki) == ok[i]
        np.testing.assert_allclose(qi, q[i], rtol=1e-12, atol=1e-12 * scale, equal_nan=True)
        if not ok[i]:
            continue
        for one, many in ((mech.jacobian(qi, x[i]), jac[i]), (mech.force_map(qi, x[i]), amap[i]),
                          (mech.link_points(qi), pts[i])):
            np.testing.assert_allclose(one, many, rtol=1e-10, atol=1e-10 * np.nanmax(np.abs(many)),
                                       equal_nan=True)
        assert bool(mech.feasible(qi, x[i])) == feas[i]
        assert int(mech.singularity(qi, x[i])) == codes[i]
        np.testing.assert_array_equal(mech.singular_legs(qi, x[i]), legs[i])


@pytest.mark.parametrize("mech, preset", CASES)
def test_unreachable_and_non_finite_input_is_masked_without_warnings(mech, preset):
    x = _samples(mech, preset, 50, seed=5)[:3]
    scale = _device_scale(mech, x)
    far = np.full((1, mech.task_dim), 0.0)
    far[0, [i for i, u in enumerate(mech.task_units) if u == "m"]] = 1e3 * scale
    bad = np.array([[np.nan] * mech.task_dim, [np.inf] * mech.task_dim])
    pts = np.concatenate([x, far, bad])
    q, ok = mech.inverse(pts)                    # filterwarnings = error: no warning may escape
    assert ok[:3].all() and not ok[-2:].any()
    assert np.all(np.isnan(q[~ok]))
    feas = np.zeros(len(pts), bool)
    feas[ok] = mech.feasible(q[ok], pts[ok])
    assert feas[:3].all() and not feas[3:].any()
    assert not mech.feasible(np.full((2, mech.n_joints), np.nan)).any()
    back, fok = mech.forward(np.array([[np.nan] * mech.n_joints, [np.inf] * mech.n_joints]))
    assert not fok.any() and np.all(np.isnan(back))
    jac = mech.jacobian(q[-2:], pts[-2:])
    assert jac.shape == (2, mech.task_dim, mech.n_joints)


# -- statics and singularities ----------------------------------------------------------------
@pytest.mark.parametrize("mech, preset", CASES)
def test_force_map_shape_and_square_statics(mech, preset):
    x, _ = _regular(mech, _samples(mech, preset, 100, seed=6, orientation=0.2))
    assert len(x) >= 5
    q, _ = mech.inverse(x)
    a = mech.force_map(q, x)
    jac = mech.jacobian(q, x)
    assert a.shape == jac.shape == (len(x), mech.task_dim, mech.n_joints)
    if not mech.is_redundant:
        # w = A tau and tau = J^T w: A = J^-T, so A^T J = I (dimensionless after joint scaling).
        joint = _joint_scale(mech, _device_scale(mech, x))
        prod = np.swapaxes(a, -1, -2) @ jac * joint[None, :] / joint[:, None]
        np.testing.assert_allclose(prod, np.broadcast_to(np.eye(mech.n_joints), prod.shape), atol=1e-8)
    else:
        # Virtual work for consistent motions: tau . qdot = w . xi with qdot = K xi, i.e. J A^T = I.
        np.testing.assert_allclose(jac @ np.swapaxes(a, -1, -2),
                                   np.broadcast_to(np.eye(mech.task_dim), (len(x),) + (mech.task_dim,) * 2),
                                   atol=1e-8)


@pytest.mark.parametrize("mech, preset", CASES)
def test_singularity_codes_and_legs(mech, preset):
    x = _samples(mech, preset, 100, seed=7)
    q, _ = mech.inverse(x)
    codes = mech.singularity(q, x)
    legs = mech.singular_legs(q, x)
    assert codes.shape == (len(x),) and codes.dtype == np.int8
    assert legs.shape == (len(x), mech.n_joints) and legs.dtype == bool
    if mech.singularity_classes:
        assert np.all((codes >= 0) & (codes < len(mech.singularity_classes)))
        assert mech.singularity_classes[0] == "none"
    else:
        assert not codes.any() and not legs.any()


@pytest.mark.parametrize("mech, preset", CASES)
def test_link_points_shape(mech, preset):
    x = _samples(mech, preset, 50, seed=8)[:4]
    q, _ = mech.inverse(x)
    pts = mech.link_points(q)
    assert pts.ndim == 3 and pts.shape[0] == len(x) and pts.shape[2] in (2, 3)
    assert np.all(np.isfinite(pts))
    assert mech.link_points(q[0]).shape == pts.shape[1:]
    assert mech.link_points(q.reshape(2, 2, -1)).shape == (2, 2) + pts.shape[1:]


# -- parameters -------------------------------------------------------------------------------
@pytest.mark.parametrize("mech, preset", CASES)
def test_replace_round_trip(mech, preset):
    fields = {f.name: getattr(mech.params, f.name) for f in dataclasses.fields(mech.params)}
    same = mech.replace(**fields)
    assert same == mech and hash(same) == hash(mech) and same is not mech
    name = next(info.name for info in mech.PARAM_INFO if not info.choices and not info.is_vector)
    changed = mech.replace(**{name: fields[name] * 1.01})
    assert changed != mech and changed.replace(**{name: fields[name]}) == mech
    # Display units (mm, deg) round trip exactly: what ``show`` prints is what a preset reads.
    shown = {info.name: value for info, value in mech.parameter_table()}
    assert mech.replace_display(**shown) == mech
    with pytest.raises(ValueError, match="no parameter"):
        mech.replace(no_such_parameter=1.0)


def _family_tokens(kind: str) -> set[str]:
    """How a description could name the family ``kind``: its registry key and class name, with
    case, spaces, hyphens and underscores dropped ("Five-bar", "five bar" and "FiveBar" alike)."""
    return {_squash(kind), _squash(MECHANISMS[kind].__name__)}


def _squash(text: str) -> str:
    return "".join(ch for ch in text.lower() if ch.isalnum())


@pytest.mark.parametrize("kind", sorted(MECHANISMS))
def test_parameter_descriptions_do_not_name_another_family(kind):
    # A tooltip copied from another model reads as if the parameter were that device's
    # (the Inverse3's proximal length once said "Five-bar proximal link length l1").
    others = set().union(*(_family_tokens(k) for k in MECHANISMS if k != kind)) - _family_tokens(kind)
    for info in MECHANISMS[kind].PARAM_INFO:
        named = sorted(token for token in others if token in _squash(info.description))
        assert not named, f"{kind}.{info.name}: {info.description!r} names {named}"


# -- singular poses: where a model classes a pose singular, every number takes its singular limit --

def _last_reachable(mech, x0, direction, span):
    """The last reachable point from the reachable ``x0`` (m,) along ``direction`` within ``span`` (m),
    bisected to adjacent doubles: where the inverse kinematics folds, an inverse singularity."""
    lo, hi = 0.0, float(span)
    d = np.asarray(direction, float)
    reach = lambda s: bool(mech.inverse(x0 + s * d)[1])      # noqa: E731
    assert reach(lo) and not reach(hi), "the ray must leave the reach"
    while True:
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            return x0 + lo * d
        lo, hi = (mid, hi) if reach(mid) else (lo, mid)


def _singular_poses(kind, mech):
    """Task points the model classes inverse-singular, built from its singularity analysis."""
    z = np.array([0.0, 0.0, 1.0])
    if kind == "fivebar":
        # Both legs stretched on the symmetry axis: the reach boundary straight up from (0, a1).
        return [_last_reachable(mech, np.array([0.0, mech.params.proximal]), [0.0, 1.0], 1.0)]
    if kind == "delta":
        # singular_loci's "all_inverse" points lie just inside a fold of the IK: step out to it.
        out = []
        for x0 in mech.singular_loci()["all_inverse"]:
            for d in (z, -z):
                if not mech.inverse(x0 + 1e-6 * d)[1]:
                    out.append(_last_reachable(mech, x0, d, 1e-6))
        return out
    if kind == "serial_rrr":
        # singular_loci's "inverse" points sit 1e-9 (l1 + l2) off the base axis: put them on it.
        # (The ends, z = +-(l1 + l2), are also the stretched elbow's fold: left out.)
        pts = mech.singular_loci(samples=41)["inverse"][1:40] * np.array([0.0, 0.0, 1.0])
        return [x for x in pts if mech.inverse(x)[1]]
    if kind == "inoue":
        # No loci of its own; straight up from home the IK folds where a leg stretches.
        home = mech.home_pose()
        return [_last_reachable(mech, home, np.eye(6)[2], 1.0)]
    raise AssertionError(f"no singular pose constructed for {kind!r}: add one here")


def _singular_cases():
    from metrics.quantities import singularity_families
    return [case for case in CASES if kind_of(case.values[0]) in singularity_families()]


@pytest.mark.parametrize("mech, preset", _singular_cases())
def test_a_pose_classed_singular_takes_the_singular_limits_in_pose_and_map(mech, preset):
    # The five-bar's rule for every family: a singular actuator's Jacobian column is exactly 0,
    # so its facet is at infinity, the condition number is inf, the parallelepiped is a slab
    # (anisotropic force inf, except the zero-moment slice of a wrench device, bounded by design:
    # metrics.suprema.ORIENTED_BOUNDED_NEAR_INVERSE), and with every actuator singular (J = 0) the
    # isotropic force is inf too. Before, the Falcon's stretched knees gave 1.6e16 N.
    from metrics.pose import analyse_pose
    from metrics.quantities import evaluate
    from metrics.suprema import finite_at_inverse

    poses = _singular_poses(kind_of(mech), mech)
    assert poses, "no singular pose found"
    names = ("condition_number", "manipulability", "isotropic_force", "anisotropic_force")
    finite = finite_at_inverse(mech, names)
    for x in poses:
        report = analyse_pose(mech, x)
        assert report.reachable and report.singularity_name == "inverse", (x, report.singularity_name)
        legs = [mech.joint_names.index(name) for name in report.singular_legs]
        assert legs, x
        jac = np.asarray(report.jacobian)
        assert np.all(jac[:, legs] == 0.0), jac
        assert np.all(np.isfinite(np.delete(jac, legs, axis=1)))
        assert report.condition_number == np.inf and report.manipulability == 0.0
        assert np.all(report.facet_distances[legs] == np.inf)
        every = len(legs) == mech.n_joints
        if every:
            assert report.isotropic_force == np.inf
        else:
            assert np.isfinite(report.isotropic_force)
        if "anisotropic_force" not in finite:
            assert report.anisotropic_force == np.inf
        else:           # the zero-moment slice, bounded by the other actuators' slabs
            assert np.isfinite(report.anisotropic_force) and np.isfinite(report.anisotropic_moment)
        # A map computes the same numbers at that point (the quantity graph's jacobian node);
        # maps hold feasible points only (a stretched knee may be outside the joint limits).
        values = evaluate(mech, np.asarray(x)[None], names).values
        for name in names:
            want = [getattr(report, name) if report.feasible else np.nan]
            assert np.array_equal(values[name], want, equal_nan=True), name


def test_a_typed_value_is_refused_in_the_unit_it_was_typed_in():
    """Before: a typed -5 mm came back as "got -0.005" (m) in the app's status bar."""
    from resources import load_preset

    mech = load_preset("inverse3_prototype").mechanism
    with pytest.raises(ValueError, match=r"proximal_length must be a positive finite number in mm, got -5$"):
        mech.replace_display(proximal_length=-5)
