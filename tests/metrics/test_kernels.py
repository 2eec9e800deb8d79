"""The compiled kernels (``metrics.kernels``) give the numpy path's numbers: feasible set, labels, values.

References: the numpy path itself (``kernels.use_compiled(False)``), which stays the reference of
every formula. Both paths evaluate the same expressions in the same order, so they can differ
only where a transcendental function (``atan2``, ``acos``, ``sin``, ``cos``; libm in the kernel,
numpy's loops in the reference, each within 1 ulp of the exact value) returns a different last
bit. The tolerances below follow from that:

- joints: each IK angle is a sum of at most three such results of magnitude below 2 pi, so two
  paths differ by at most ``8 pi eps`` (a few ulps of 2 pi) per angle;
- J: each entry is a product of at most three factors each carrying one such result, so its
  relative perturbation is below ``DJ = 16 eps`` of ``|J|_F`` (1 ulp in each of the ~6 trig
  results, a factor up to 2 from the angles' own difference, plus the products' rounding);
- a quantity then moves by its condition times ``DJ``: ``kappa`` for the condition number (plus
  the closed form's arccos step: a 1-ulp change in the angle of the trigonometric eigenvalue
  formula moves ``lambda_3`` by at most ``2 pi eps p`` with ``p <= lambda_1``, so ``sigma_3`` by
  ``pi eps kappa^2`` relative), ``|J|_F / min_u |J[:, u]|`` for the isotropic force (a column
  norm's relative error), and the Frobenius condition ``|J|_F |J^-1|_F`` for the anisotropic force
  (the inverse's relative error). The Inverse3 kernel takes that step's two cosines as a cube root
  (``square3.third_cosines3``, within 3 eps of the exact ones; numpy's ``cos`` of its rounded angle
  within 4 eps: arccos's ulp over 3, the sum's and ``cos``'s roundings): their difference, under
  7 eps, moves ``lambda_3`` by at most ``14 eps p`` and ``sigma_3`` by ``7 eps kappa^2`` relative,
  inside the tolerances' ``pi kappa^2 DJ`` (``DJ = 16 eps``).

The Inverse3 kernel departs from "the same expressions" in one place: it forms J's sines and
cosines from ratios of the point's coordinates (``cos th3 = u / a3``, ``sin h = sqrt((1 - c)(1 + c))``
with ``c`` the elbow's cosine, ``cos th0`` from the rotated point), where the numpy path takes
``sin`` and ``cos`` of its IK angles. So the two also differ by the numpy IK's rounding carried into
J (``_inverse3_dj``): each of its angles is within ``8 pi eps`` of the kernel's (asserted on the
joints), which moves a sine or cosine by as much, and J's entries are products of two such factors
(``2 x 8 pi eps``); and ``h = acos(c)`` amplifies the rounding of ``c`` (a few ulps of 1) by acos's
slope ``1 / |sin h|``, which grows without bound at the two reach spheres (``sin h = 0``), hence a
per-point ``8 eps / |sin h|`` on top. ``test_near_the_reach_spheres`` puts points there. Both are
relative to the derivatives by ``th3`` and by ``h``, whose half sum and half difference are J's columns
1 and 2: ``|d_th3|^2 + |d_h|^2 = 2 (|J[:, 1]|^2 + |J[:, 2]|^2)``, so each is at most ``sqrt(2) |J|_F``
and their errors are at most ``sqrt(2)`` times as much of ``|J|_F``. (The points where this shows
have ``kappa`` 50-80 and two close singular values: the kernel computes them since ``svd3``.)

Given the same J, the polytope quantities use no transcendental function at all: there the kernel
must give the numpy path's numbers bit for bit. Hard, singular and far-from-unit-scale points are
handed back to the numpy path, so there the two are identical by construction, which is checked.
"""
from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest

from kinematics import Inverse3
from metrics import kernels, statistics
from metrics.kernels import inverse3 as inverse3_kernel
from metrics.kernels import square3
from metrics.linalg import SAFE_SCALE
from metrics.loading import DEFAULT_LOADING
from metrics.quantities import available_quantities, evaluate
from metrics.workspace import GridSpec, compute_map
from resources import load_preset

EPS = np.finfo(float).eps
DJ = 16 * EPS
NAMES = ("condition_number", "inverse_condition_number", "manipulability", "isotropic_force",
         "anisotropic_force", "spatial_resolution", "bottleneck")
ROOT = Path(__file__).resolve().parents[2]


def _both(mech, pts, names=NAMES):
    with kernels.use_compiled(True):
        fast = evaluate(mech, pts, names)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, names)
    return fast, ref


def _designs():
    base = Inverse3()
    return [base, base.replace(proximal_length=0.16, distal_length=0.15), base.replace(base_branch="front"),
            base.replace(base_branch="back", gear_ratios=(3.0, 9.0, 1.5), lower_limits=(-6.0,) * 3,
                         upper_limits=(6.0,) * 3),
            base.replace(min_link_spread=0.05, max_link_spread=3.1)]


def _box_points(rng, count):
    """Points over the reach of the default design and beyond: reachable, unreachable, near the base axis."""
    lo, hi = np.array([-0.4, -0.4, -0.25]), np.array([0.4, 0.4, 0.6])
    return lo + (hi - lo) * rng.random((count, 3))


def _inverse3_dj(joints):
    """Per-point relative bound on the Inverse3 paths' J (module docstring): ``DJ``, the IK angles'
    ``2 x 8 pi eps``, and the elbow's ``8 eps / |sin h|`` (``h = (q1 - q2) / 2``), the last two times
    ``sqrt(2)`` (J's columns from the derivatives by ``th3`` and ``h``); ``joints`` (k, 3)."""
    sin_h = np.abs(np.sin(0.5 * (joints[:, 1] - joints[:, 2])))
    return DJ + math.sqrt(2) * (16 * math.pi * EPS + 8 * EPS / sin_h)


def _limit_margin(mech, q, x):
    """Distance (rad, or m for the body constraint) of each pose from the nearest feasibility bound."""
    p = mech.params
    lo, hi = np.array(p.lower_limits), np.array(p.upper_limits)
    margin = np.min(np.minimum(np.abs(q - lo), np.abs(q - hi)), axis=-1)
    spread = np.abs(q[:, 1] - q[:, 2])
    margin = np.minimum(margin, np.minimum(np.abs(spread - p.min_link_spread), np.abs(spread - p.max_link_spread)))
    radial = x[:, 0] * np.cos(q[:, 0]) + x[:, 1] * np.sin(q[:, 0])
    return np.minimum(margin, np.minimum(np.abs(radial - p.body_radius), np.abs(x[:, 2] - p.body_height)))


def _relative_tolerances(jac, kappa, dj):
    """Per-point relative bounds of the compiled quantities (module docstring): J's relative error
    ``dj`` (a scalar or per point) through each quantity's condition, ``jac`` (k, m, m) numpy's J."""
    fro = np.linalg.norm(jac, axis=(-2, -1))
    cols = np.linalg.norm(jac, axis=-2).min(axis=-1)
    fro_cond = fro * np.linalg.norm(np.linalg.inv(jac), axis=(-2, -1))
    return {"spatial_resolution": fro / cols * dj,
            "condition_number": (math.pi * kappa ** 2 + kappa) * dj + 10 * EPS * kappa ** 2,
            "inverse_condition_number": (math.pi * kappa ** 2 + kappa) * dj + 10 * EPS * kappa ** 2,
            "manipulability": 3 * kappa * dj + 10 * EPS * kappa ** 2,
            "isotropic_force": fro / cols * dj,
            "anisotropic_force": fro_cond * dj}


@pytest.mark.parametrize("design", range(5))
def test_compiled_evaluate_equals_the_numpy_path(design):
    mech = _designs()[design]
    rng = np.random.default_rng(design)
    pts = np.concatenate([_box_points(rng, 20000),
                          load_preset("inverse3_prototype").grid.with_resolution(120).points(mech.task_names)
                          .reshape(-1, 3)])
    fast, ref = _both(mech, pts)
    assert fast.computed == ref.computed
    # The feasible sets: the same, except (in exact arithmetic) at a pose within a few ulps of a bound.
    with np.errstate(invalid="ignore"):
        q = np.where(np.isnan(ref.joints), fast.joints, ref.joints)
        border = _limit_margin(mech, q, pts) <= 8 * math.pi * EPS
    assert not np.any((fast.feasible != ref.feasible) & ~border)
    both = fast.feasible & ref.feasible
    assert both.sum() > 1000
    assert np.all(np.abs(fast.joints[both] - ref.joints[both]) <= 8 * math.pi * EPS)
    assert np.all(np.isnan(fast.joints[~fast.feasible]))
    with kernels.use_compiled(False):
        jac = evaluate(mech, pts[both], ["jacobian"]).values["jacobian"]
    tol = _relative_tolerances(jac, ref.values["condition_number"][both], _inverse3_dj(ref.joints[both]))
    for name, rel in tol.items():
        a, b = fast.values[name][both], ref.values[name][both]
        assert np.all(np.isnan(fast.values[name][~both])) and np.all(np.isnan(ref.values[name][~both]))
        assert np.all(np.abs(a - b) <= rel * np.abs(b)), name
    # A bottleneck moves only where two facets are within the tie rule's reach of each other.
    assert np.array_equal(fast.values["bottleneck"][~both], ref.values["bottleneck"][~both])
    assert np.mean(fast.values["bottleneck"][both] == ref.values["bottleneck"][both]) > 0.999


@pytest.mark.parametrize("design", range(5))
def test_near_the_reach_spheres(design):
    """Points 1e-15 .. 1e-1 (relative) either side of the outer and inner reach spheres, where the
    numpy IK's elbow angle carries its largest rounding (``_inverse3_dj``): the same feasible set
    away from a bound, and every quantity within its tolerance."""
    mech = _designs()[design]
    p = mech.params
    rng = np.random.default_rng(50 + design)
    n = 20000
    az, el = rng.uniform(-math.pi, math.pi, n), rng.uniform(-1.2, 1.2, n)
    feasible = 0
    for radius in (p.proximal_length + p.distal_length, abs(p.proximal_length - p.distal_length)):
        r = radius * (1 + 10.0 ** rng.uniform(-15, -1, n) * rng.choice([-1.0, 1.0], n))
        u, w, c = r * np.cos(el), r * np.sin(el), p.plane_offset     # the arm's plane, rotated by az
        pts = np.stack([u * np.cos(az) - c * np.sin(az), u * np.sin(az) + c * np.cos(az), w + p.base_height], 1)
        fast, ref = _both(mech, pts)
        with np.errstate(invalid="ignore"):
            q = np.where(np.isnan(ref.joints), fast.joints, ref.joints)
            border = _limit_margin(mech, q, pts) <= 8 * math.pi * EPS
        assert not np.any((fast.feasible != ref.feasible) & ~border)
        both = fast.feasible & ref.feasible
        feasible += int(both.sum())
        if not both.any():
            continue
        with kernels.use_compiled(False):
            jac = evaluate(mech, pts[both], ["jacobian"]).values["jacobian"]
        tol = _relative_tolerances(jac, ref.values["condition_number"][both], _inverse3_dj(ref.joints[both]))
        for name, rel in tol.items():
            a, b = fast.values[name][both], ref.values[name][both]
            assert np.all(np.abs(a - b) <= rel * np.abs(b)), name
    assert feasible > 100


def test_the_polytope_quantities_of_one_jacobian_are_bit_for_bit_numpys():
    """Given the same J, the kernel's column norms, inverse and vertices are the numpy kernels' operations."""
    mech = Inverse3()
    rng = np.random.default_rng(7)
    pts = _box_points(rng, 20000)
    with kernels.use_compiled(False):
        ref = evaluate(mech, pts, ("jacobian", "isotropic_force", "anisotropic_force", "bottleneck"))
    jac = ref.values["jacobian"][ref.feasible]
    out = np.full((len(square3.COLUMNS), len(jac)), np.nan)
    bneck = np.full(len(jac), -1, np.int16)
    t = mech.torque_limits()
    back = np.array([square3.quantities3(*j.reshape(-1), t, np.ones(3), out, bneck, i, False, True, True)
                     for i, j in enumerate(jac)])
    assert back.mean() < 0.01
    keep = ~back
    for name in ("isotropic_force", "anisotropic_force"):
        np.testing.assert_array_equal(out[square3.COLUMNS.index(name), keep], ref.values[name][ref.feasible][keep])
    np.testing.assert_array_equal(bneck[keep], ref.values["bottleneck"][ref.feasible][keep])


@pytest.mark.parametrize("torque", [1e-300, 1e-150, 1e150, 1e300])
def test_extreme_torques_are_handed_back_or_scale_exactly(torque):
    mech = Inverse3().replace(motor_torques=(torque,) * 3)
    pts = load_preset("inverse3_prototype").grid.with_resolution(60).points(mech.task_names).reshape(-1, 3)
    fast, ref = _both(mech, pts)
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    for name in ("isotropic_force", "anisotropic_force"):
        a, b = fast.values[name][ref.feasible], ref.values[name][ref.feasible]
        assert np.all(np.isfinite(a)) and np.all(a > 0)
        # Forces scale with the torque: exactly where both are formed as given, else numpy's rescaled value.
        np.testing.assert_allclose(a, b, rtol=64 * EPS * 100, atol=0)


def test_handed_back_points_get_the_numpy_values_and_labels_exactly():
    """Near the stretched and folded legs J is ill-conditioned (kappa > 100): numpy's LAPACK path decides."""
    mech = Inverse3().replace(min_link_spread=1e-3, max_link_spread=3.14)
    pts = load_preset("inverse3_prototype").grid.with_resolution(300).points(mech.task_names).reshape(-1, 3)
    kernel = kernels.find(mech, NAMES, DEFAULT_LOADING)
    _, _, _, _, back = kernel.run(pts)
    assert back.sum() > 0           # 11 here: the near-repeated singular values are the kernel's (``svd3``)
    fast, ref = _both(mech, pts[back])
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    for name in NAMES:
        np.testing.assert_array_equal(fast.values[name], ref.values[name], err_msg=name)
    assert np.any(ref.values["condition_number"][ref.feasible] > 100)


@pytest.mark.parametrize("key", ["inverse3_prototype", "phantom_premium_15"])
def test_one_thread_and_every_thread_give_the_same_map(key):
    preset = load_preset(key)
    grid = preset.grid.with_resolution(301)
    # The mass quantities and (the PHANToM's motor speeds) the isotropic velocity run in the kernels too.
    names = ("condition_number", "isotropic_force", "anisotropic_force", "inverse_condition_number", "bottleneck",
             "apparent_mass_min", "apparent_mass_max", "isotropic_acceleration")
    if preset.mechanism.joint_speed_limits() is not None:
        names += ("isotropic_velocity",)
    many = compute_map(preset.mechanism, grid, names, threads=True)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        one = compute_map(preset.mechanism, grid, names, threads=True)
        streamed = compute_map(preset.mechanism, grid, names, threads=True, keep=False)
    finally:
        numba.set_num_threads(before)
    serial = compute_map(preset.mechanism, grid, names, threads=False)
    for other in (one, serial):
        np.testing.assert_array_equal(other.feasible, many.feasible)
        for name in names:
            np.testing.assert_array_equal(other.values[name], many.values[name], err_msg=name)
        assert other.stats == many.stats and other.errors == many.errors and other.gci == many.gci
    streamed_many = compute_map(preset.mechanism, grid, names, threads=True, keep=False)
    assert streamed.stats == streamed_many.stats


def test_compiled_map_statistics_equal_the_numpy_map():
    """Counts, extremes and their places exactly; the mean and SD to the summations' rounding."""
    preset = load_preset("inverse3_prototype")
    grid = preset.grid.with_resolution(401)
    names = ("condition_number", "isotropic_force", "anisotropic_force", "inverse_condition_number")
    for keep in (True, False):
        fast = compute_map(preset.mechanism, grid, names, keep=keep)
        with kernels.use_compiled(False):
            ref = compute_map(preset.mechanism, grid, names, keep=keep)
        assert fast.feasible_points == ref.feasible_points
        n = ref.feasible_points
        for name in names:
            a, b = fast.stats[name], ref.stats[name]
            assert (a.count, a.singular_points, a.argmin, a.argmax) == (b.count, b.singular_points, b.argmin, b.argmax)
            # Values differ by the kernels' few ulps times the computation's condition (module docstring),
            # at most (pi kappa^2 + kappa) DJ + 10 eps kappa^2 over this map (the largest kappa: its
            # condition number's maximum, 9.5; the force figures' conditions |J|_F / min |J_u| and the
            # Frobenius condition are within sqrt(3) kappa and 3 kappa of it); the sums differ by
            # log2(n) eps (numpy's pairwise mean) against 2 eps (ours, compensated).
            kappa = ref.stats["condition_number"].max
            value_tol = (math.pi * kappa ** 2 + 3 * kappa) * DJ + 10 * EPS * kappa ** 2
            assert a.min == pytest.approx(b.min, rel=value_tol) and a.max == pytest.approx(b.max, rel=value_tol)
            assert a.mean == pytest.approx(b.mean, rel=value_tol + (math.log2(n) + 2) * EPS)
            assert a.sd == pytest.approx(b.sd, rel=value_tol * b.mean / b.sd + (math.log2(n) + 2) * EPS * 4)
            for f in statistics.QUANTILES:
                tol = (0 if keep else 2 * statistics.QUANTILE_REL_ERROR) + value_tol
                assert abs(getattr(a, f) - getattr(b, f)) <= tol * abs(getattr(b, f)), (name, f)


@pytest.mark.parametrize("magnitude", [1e-300, 1.0, 1e300])
def test_compiled_partials_equal_chunk_partial(magnitude):
    rng = np.random.default_rng(3)
    shape = (37, 41)
    k = 1200
    index = np.sort(rng.choice(shape[0] * shape[1], k, replace=False))
    # The second quantity spans ~80 binades at unit scale: wider than the dense histogram, sorted instead.
    width = 30.0 if magnitude == 1.0 else 0.5
    values = [magnitude * (1.0 + rng.random(k)), magnitude * np.exp(rng.normal(0, width, k)) * rng.choice([-1, 1], k)]
    values[0][::97] = np.inf
    regular = rng.random(k) < 0.9
    singular = ~regular & (rng.random(k) < 0.5)
    bounded = singular & (rng.random(k) < 0.5)
    parts = kernels.chunk_partials(values, regular, singular, bounded, index, shape, (True, True, True, True),
                                   [True, False], histogram=True, threads=True)
    ijk = np.unravel_index(index, shape)
    # The full grid, the half grids (every 2nd point from 0 and 1) and the quarter grids (every 4th from 0 and 2).
    for q, v in enumerate(values):
        assert len(parts[q]) == 5
        for (stride, start), part in zip(((1, 0), (2, 0), (2, 1), (4, 0), (4, 2)), parts[q]):
            member = np.logical_and.reduce([c % stride == start for c in ijk])
            sub_shape = tuple((n - start + stride - 1) // stride for n in shape)
            at = np.ravel_multi_index(tuple((c[member] - start) // stride for c in ijk), sub_shape)
            ref = statistics.chunk_partial(v[member], regular[member], singular[member], at, histogram=True,
                                           bounded=bounded[member] if q == 0 else None)
            assert (part.count, part.min, part.max, part.argmin, part.argmax, part.singular) == (
                ref.count, ref.min, ref.max, ref.argmin, ref.argmax, ref.singular)
            np.testing.assert_array_equal(part.singular_index, ref.singular_index)
            # Sums: numpy's pairwise within (log2 k + 1) eps of sum |v|, ours within 2 eps.
            bound = (math.log2(k) + 3) * EPS
            finite = regular[member] & np.isfinite(v[member])
            spread = np.sum(np.abs(v[member][finite])) / abs(np.sum(v[member][finite]))
            assert part.mean == pytest.approx(ref.mean, rel=bound * spread, abs=0)
            if ref.count:      # squared deviations in one power-of-two scale (exact rescaling)
                assert part.m2 * (part.scale / ref.scale) ** 2 == pytest.approx(ref.m2, rel=4 * bound * spread ** 2)
            for mine, theirs in zip((part.keys, part.counts, part.lows, part.highs),
                                    (ref.keys, ref.counts, ref.lows, ref.highs)):
                np.testing.assert_array_equal(mine, theirs)


def test_only_the_requested_branches_run_and_unknown_requests_take_the_numpy_path():
    mech = Inverse3()
    kernel = kernels.find(mech, ("condition_number",), DEFAULT_LOADING)
    assert (kernel.want_sv, kernel.want_columns, kernel.want_vertices) == (True, False, False)
    pts = load_preset("inverse3_prototype").grid.with_resolution(50).points(mech.task_names).reshape(-1, 3)
    _, _, values, classes, _ = kernel.run(pts)
    assert np.all(np.isnan(values[square3.COLUMNS.index("isotropic_force")]))
    assert np.all(classes["bottleneck"] == -1)
    assert kernels.find(mech, ("force_ellipsoid_min_radius",), DEFAULT_LOADING) is None
    # A request the kernel covers in part runs in numpy whole (metrics.kernels: measured faster).
    assert kernels.find(mech, ("isotropic_force", "force_ellipsoid_min_radius"), DEFAULT_LOADING) is None
    assert kernels.find(load_preset("twin_pantograph").mechanism, ("condition_number",), DEFAULT_LOADING) is None
    # The Stewart platform's kernel computes its wrench quantities, not the force ellipsoid.
    assert kernels.find(load_preset("stewart_platform").mechanism, ("force_ellipsoid_min_radius",),
                        DEFAULT_LOADING) is None
    for key, size in (("phantom_omni", 14), ("novint_falcon", 41), ("haply_2diy", 11)):
        other = load_preset(key).mechanism
        kernel = kernels.find(other, ("condition_number", "singularity"), DEFAULT_LOADING)
        assert kernel is not None and kernel.params.shape == (size,)
    with kernels.use_compiled(False):
        assert kernels.find(mech, ("condition_number",), DEFAULT_LOADING) is None
    assert inverse3_kernel.pack(mech).shape == (16,)


def test_an_unwritable_cache_compiles_in_memory(tmp_path):
    """Where numba finds no writable cache directory it refuses ``cache=True``: the kernels compile in memory."""
    script = textwrap.dedent("""
        import numba
        real = numba.njit
        def refusing(*args, cache=False, **kwargs):
            if cache:
                raise RuntimeError("cannot cache function 'f': no locator available for file 'f.py'")
            return real(*args, **kwargs)
        numba.njit = refusing
        import numpy as np
        from kinematics import Inverse3
        from metrics import kernels
        from metrics.kernels import jit
        from metrics.quantities import available_quantities, evaluate
        ev = evaluate(Inverse3(), np.array([[0.2, 0.0223, 0.25]]), ["isotropic_force"])
        print(jit.CACHED, bool(ev.feasible[0]), kernels.compile_seconds() > 0)
    """)
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=600,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "True", "True"]


def test_a_kernels_cache_entry_is_keyed_on_every_file_its_code_comes_from(tmp_path, monkeypatch):
    """numba keys a cached function on its own file; the kernels' entries are keyed on ``jit.SOURCES``,
    which holds every module of the package and every module they import constants from, so an edit
    to a helper or a limit recompiles them instead of loading stale machine code."""
    import ast

    from metrics.kernels import inverse3, jit
    package = Path(jit.__file__).parent
    for path in package.glob("*.py"):
        assert path in jit.SOURCES, path
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("metrics."):
                if not node.module.startswith("metrics.kernels"):
                    assert package.parent / (node.module.split(".")[1] + ".py") in jit.SOURCES, (path, node.module)
    assert inverse3.run_serial._cache._impl._locator.get_source_stamp() == jit.sources_stamp()
    copies = []
    for i, path in enumerate(jit.SOURCES):
        copies.append(tmp_path / f"{i}_{path.name}")
        copies[-1].write_bytes(path.read_bytes())
    monkeypatch.setattr(jit, "SOURCES", tuple(copies))
    jit.sources_stamp.cache_clear()
    try:
        before = jit.sources_stamp()
        jit.sources_stamp.cache_clear()
        copies[-1].write_bytes(copies[-1].read_bytes() + b"# one more byte")
        assert jit.sources_stamp() != before
    finally:
        jit.sources_stamp.cache_clear()


# -- the five-bar -------------------------------------------------------------------------------
FIVEBAR_NAMES = ("condition_number", "inverse_condition_number", "manipulability", "isotropic_force",
                 "anisotropic_force", "bottleneck", "singularity")


def _fivebar_column_error(mech, q: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Bound on the relative difference of ``|J[:, u]|`` between the two paths, shape (N, 2).

    ``J = adj(J_p) diag(jtheta) / det J_p``, so column u's norm is ``|p_(1-u)| |jtheta_u| / |det J_p|``
    with ``p_i = x - B_i`` the distal vectors (the adjugate's column u is leg 1 - u's ``p`` turned a
    quarter). Where a leg nears its stretched or folded pose ``jtheta_u = a1 p_u . t_u`` (``t_u =
    (-sin q_u, cos q_u)``) cancels, and where the distal links near parallel ``det`` does: each
    amplifies the inputs' difference by its own condition, which ``DJ`` (a relative error of
    ``|J|_F``, for products of trig results) does not hold. From the inputs:

    - each angle differs by at most ``8 pi eps`` (asserted) and each sine or cosine is within an ulp
      per path: ``dc = (8 pi + 2) eps`` on ``(cos q, sin q)`` and on ``t``;
    - ``B = base + a1 (cos, sin)`` and ``p = x - B`` round once each per path:
      ``dp = a1 dc + 2 eps (|B|_max + |p|_max)`` per entry of ``p``;
    - ``p_u . t_u`` moves by ``dp |t_u|_1 + dc |p_u|_1 + 2 (2 eps) (|p_u0 t_u0| + |p_u1 t_u1|)``, ``det`` by
      ``dp (sum of |p|'s four entries) + 2 (2 eps) (|p_00 p_11| + |p_01 p_10|)``, ``|p_(1-u)|`` by ``sqrt(2) dp``;
    - the entries' product and quotient and the norm's square root round 4 eps per path.

    The relative changes add (first order; every term is below 1e-9 on the tested points).
    """
    elbows = mech.elbows(q)
    p = x[:, None, :] - elbows
    t = np.stack([-np.sin(q), np.cos(q)], axis=-1)
    dc = (8 * math.pi + 2) * EPS
    dp = mech.params.proximal * dc + 2 * EPS * (np.abs(elbows).max(axis=(-2, -1)) + np.abs(p).max(axis=(-2, -1)))
    dot = np.sum(p * t, axis=-1)
    d_dot = dp[:, None] * np.abs(t).sum(-1) + dc * np.abs(p).sum(-1) + 4 * EPS * np.abs(p * t).sum(-1)
    det = p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]
    products = np.abs(p[:, 0, 0] * p[:, 1, 1]) + np.abs(p[:, 0, 1] * p[:, 1, 0])
    d_det = dp * np.abs(p).sum(axis=(-2, -1)) + 4 * EPS * products
    other = np.linalg.norm(p[:, ::-1], axis=-1)
    return np.sqrt(2) * dp[:, None] / other + d_dot / np.abs(dot) + (d_det / np.abs(det))[:, None] + 8 * EPS


@pytest.mark.parametrize("key, mode", [("fivebar_singh", None), ("haply_2diy", None), ("fivebar_singh", "++"),
                                       ("fivebar_singh", "-+")])
def test_compiled_fivebar_equals_the_numpy_path(key, mode):
    """Same expressions, same order: the tolerances of the module docstring, with 2 x 2 J (no arccos
    in the singular values: the closed form's own error is eps kappa, linalg's table)."""
    preset = load_preset(key)
    mech = preset.mechanism if mode is None else preset.mechanism.replace(working_mode=mode)
    names = FIVEBAR_NAMES + (("spatial_resolution",) if "spatial_resolution" in available_quantities(mech) else ())
    rng = np.random.default_rng(11)
    a1, a2, a3 = mech.params.proximal, mech.params.distal, mech.params.half_base
    # On the circles where a leg stretches or folds (no step inside, unlike singular_loci): the
    # rounding puts them on either side, and the reachable ones are classed inverse.
    angle = np.linspace(0.0, 2.0 * np.pi, 2000, endpoint=False)
    ring = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    circles = [np.array([sign * a3, 0.0]) + r * ring for sign in (-1.0, 1.0) for r in (a1 + a2, abs(a1 - a2))]
    pts = np.concatenate([preset.grid.with_resolution(150).points(mech.task_names).reshape(-1, 2),
                          0.5 * rng.normal(size=(20000, 2)) * (a1 + a2), *circles])
    fast, ref = _both(mech, pts, names)
    assert fast.computed == ref.computed
    q = np.where(np.isnan(ref.joints), fast.joints, ref.joints)
    limits = mech.params.joint_limits
    border = np.zeros(len(pts), bool)
    if limits is not None:
        border = np.min(np.abs(q[:, :, None] - np.array(limits)[None]), axis=(-2, -1)) <= 8 * math.pi * EPS
    assert not np.any((fast.feasible != ref.feasible) & ~border)
    both = fast.feasible & ref.feasible
    assert both.sum() > 1000
    assert np.all(np.abs(fast.joints[both] - ref.joints[both]) <= 8 * math.pi * EPS)
    # Singularity classes: the kernel hands every singular pose back, so the labels are numpy's.
    np.testing.assert_array_equal(fast.values["singularity"][both], ref.values["singularity"][both])
    assert np.any(ref.values["singularity"][both] > 0)
    regular = both & (ref.values["singularity"] == 0)
    with kernels.use_compiled(False):
        jac = evaluate(mech, pts[regular], ["jacobian"]).values["jacobian"]
    fro = np.linalg.norm(jac, axis=(-2, -1))
    fro_cond = fro * np.linalg.norm(np.linalg.inv(jac), axis=(-2, -1))
    kappa = ref.values["condition_number"][regular]
    # The isotropic force is min_u t_u / |J[:, u]|, the spatial resolution max_u |J[:, u]| delta_u (one
    # more rounding, 2 eps over both paths): the larger of the columns' errors, since the extreme
    # column can differ between the paths.
    columns = _fivebar_column_error(mech, ref.joints[regular], pts[regular]).max(axis=-1) + 2 * EPS
    tol = {"condition_number": 2 * kappa * DJ, "inverse_condition_number": 2 * kappa * DJ,
           "manipulability": 2 * kappa * DJ, "isotropic_force": columns,
           "spatial_resolution": columns, "anisotropic_force": fro_cond * DJ}
    for name in names:
        a, b = fast.values[name], ref.values[name]
        if name in ("bottleneck", "singularity"):
            np.testing.assert_array_equal(a[~both], b[~both])
            continue
        assert np.array_equal(np.isnan(a), np.isnan(b)) and np.array_equal(np.isinf(a), np.isinf(b)), name
        np.testing.assert_array_equal(a[both & ~regular], b[both & ~regular])     # handed back: numpy's
        assert np.all(np.abs(a[regular] - b[regular]) <= tol[name] * np.abs(b[regular])), name


def test_fivebar_singular_poses_are_handed_back_and_threads_agree():
    preset = load_preset("fivebar_singh")
    mech = preset.mechanism
    names = ("condition_number", "isotropic_force", "anisotropic_force", "inverse_condition_number")
    grid = preset.grid.with_resolution(401)        # the paper's grid holds stretched legs at its nodes
    many = compute_map(mech, grid, names, threads=True)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        one = compute_map(mech, grid, names, threads=True)
    finally:
        numba.set_num_threads(before)
    with kernels.use_compiled(False):
        ref = compute_map(mech, grid, names)
    for name in names:
        np.testing.assert_array_equal(one.values[name], many.values[name], err_msg=name)
    assert one.stats == many.stats
    np.testing.assert_array_equal(many.feasible, ref.feasible)
    np.testing.assert_array_equal(many.singular, ref.singular)
    np.testing.assert_array_equal(many.inverse_singular, ref.inverse_singular)
    for name in names:
        a, b = many.stats[name], ref.stats[name]
        assert (a.count, a.singular_points, a.singular_at, a.unbounded, a.unbounded_at, a.vanishes) == (
            b.count, b.singular_points, b.singular_at, b.unbounded, b.unbounded_at, b.vanishes), name
        assert (a.argmin, a.argmax) == (b.argmin, b.argmax), name


@pytest.mark.parametrize("grid", [
    GridSpec(("x", "z"), (-0.05, -0.15), (0.35, 0.5), (997, 1003), (("y", 0.0223),)),
    GridSpec(("z", "x"), (-0.15, -0.05), (0.5, 0.35), (31, 17), (("y", 0.0223),)),
    GridSpec(("x", "y", "z"), (0.0, -0.1, 0.1), (0.2, 0.1, 0.3), (13, 7, 11)),
    GridSpec(("x", "z"), (0.0, 0.0), (1e-320, 1.0), (5, 4), (("y", 0.5),)),      # a step that underflows
])
def test_compiled_grid_points_are_gridspecs_to_the_last_bit(grid):
    names = ("x", "y", "z")
    total = math.prod(grid.resolution)
    for span in ((0, total), (total // 3, total - 1), (total - 1, total)):
        np.testing.assert_array_equal(kernels.grid_points(grid, names, span), grid.points(names, slice(*span)))
        np.testing.assert_array_equal(kernels.grid_points(grid, names, span, threads=False),
                                      grid.points(names, slice(*span)))


def test_a_request_with_nothing_for_a_kernel_loads_no_numba():
    """The pose glyphs and overlays ask for the Jacobian alone: no compile, no numba import in their process."""
    code = ("import sys, numpy as np; from kinematics import Inverse3; from metrics.quantities import evaluate; "
            "evaluate(Inverse3(), np.array([[0.2, 0.0223, 0.25]]), ['jacobian']); print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False"]


def test_a_replaced_node_sends_the_request_to_the_graph(monkeypatch):
    """A kernel computes the shipped definitions; a node replaced (here by a test's own) makes the graph run."""
    import dataclasses

    from metrics import quantities

    mech = Inverse3()
    names = ("isotropic_force",)
    assert quantities.compiled_kernel(mech, names, DEFAULT_LOADING) is not None
    node = quantities.QUANTITIES["isotropic_force"]
    monkeypatch.setitem(quantities.QUANTITIES, "isotropic_force",
                        dataclasses.replace(node, compute=lambda v, m: np.zeros(len(v["jacobian"]))))
    assert quantities.compiled_kernel(mech, names, DEFAULT_LOADING) is None


# -- the other 3-DOF force devices: serial RRR (PHANToM, Omni, WoodenHaptics) and delta (Falcon) ------------
RRR_DELTA_NAMES = ("condition_number", "inverse_condition_number", "manipulability", "isotropic_force",
                   "anisotropic_force", "bottleneck", "singularity")
#: (preset, parameter changes): every shipped preset of the two families, and their other IK branches
#: and shapes (a classical delta: no knee or platform offsets, the platform point on a sphere).
RRR_DELTA_DESIGNS = [
    ("phantom_premium_15", {}), ("phantom_omni", {}), ("woodenhaptics", {}),
    ("phantom_premium_15", {"base_branch": "front"}),
    ("phantom_premium_15", {"base_branch": "back", "lower_limits": (-3.1,) * 3, "upper_limits": (3.1,) * 3}),
    ("novint_falcon", {}), ("novint_falcon", {"knee_offset": 0.0, "platform_joint_offset": 0.0}),
    ("novint_falcon", {"arm_offset_angle": 0.0, "bar_limit": 80 * math.pi / 180}),
]


def _design(key, changes):
    mech = load_preset(key).mechanism
    return mech.replace(**changes) if changes else mech


def _design_points(key, mech, rng, count=20000):
    """The preset's grid, and random points over a box holding the reach (and beyond it)."""
    grid = load_preset(key).grid
    grid = grid.with_resolution(120 if len(grid.axes) == 2 else 30)
    if type(mech).__name__ == "Delta":
        from kinematics.delta_loci import _reach_box
        lo, hi = _reach_box(mech)
    else:
        reach = mech.params.link1_length + mech.params.link2_length
        lo, hi = np.full(3, -1.1 * reach), np.full(3, 1.1 * reach)
    return np.concatenate([grid.points(mech.task_names).reshape(-1, 3), lo + (hi - lo) * rng.random((count, 3))])


def _feasibility_margin(mech, q, x):
    """How far (rad) each pose is from the nearest feasibility bound, and the rounding allowance there.

    Both paths form the same operations; only a transcendental result's last bit may differ on
    another libm, moving each IK angle by at most ``8 pi eps``. A serial arm's limits and coupling
    limits (a difference of two angles) then move by twice that, and its branch choice
    (``|q1 - pi| < |q1|``) by as much. A delta's knee bend and bar angle are angles of the vector
    from the knee, which the arm angle moves by ``a`` times its change: their bound is ``8 pi eps``
    times ``1 + a / rho``, with ``rho >= D + b cos(bar_limit)`` the forearm's reach from the motor axis
    at any feasible pose.
    """
    p = mech.params
    if type(mech).__name__ == "Delta":
        bend, theta3 = mech.leg_angles(q, x)
        margin = np.min(np.minimum.reduce([np.abs(q - p.arm_lower), np.abs(q - p.arm_upper),
                                           np.abs(bend - p.knee_min), np.abs(bend - p.knee_max),
                                           np.abs(np.abs(theta3 - np.pi / 2) - p.bar_limit)]), axis=-1)
        lever = p.upper_arm / (p.knee_offset + p.platform_joint_offset + p.parallelogram * math.cos(p.bar_limit))
        return margin, 8 * math.pi * EPS * (1 + lever)
    lo, hi = np.array(p.lower_limits), np.array(p.upper_limits)
    margin = np.min(np.minimum(np.abs(q - lo), np.abs(q - hi)), axis=-1)
    margin = np.minimum(margin, np.abs(q[:, 1] - q[:, 2] - p.max_q2_minus_q3))
    margin = np.minimum(margin, np.abs(q[:, 2] - q[:, 1] - p.max_q3_minus_q2))
    azimuth = np.arctan2(x[:, 1], x[:, 0])
    margin = np.minimum(margin, np.abs(np.abs(azimuth) - np.pi / 2))
    return margin, 16 * math.pi * EPS


def _jacobian_error(mech, q, x):
    """Relative bound (Frobenius) on the two paths' J: ``DJ`` for the serial arm's closed form; a delta's
    ``A^-1`` (LAPACK's LU there, the adjugate here) adds ``8 kappa_F(A) eps`` (each inverse's own error is
    a small multiple of ``kappa_F(A) eps``)."""
    if type(mech).__name__ != "Delta":
        return DJ
    bars, _ = mech._velocity_matrices(q, x)
    kappa_a = np.linalg.norm(bars, axis=(-2, -1)) * np.linalg.norm(np.linalg.inv(bars), axis=(-2, -1))
    return DJ + 8 * kappa_a * EPS


@pytest.mark.parametrize("key, changes", RRR_DELTA_DESIGNS, ids=lambda v: str(v) if v else "preset")
def test_compiled_serial_rrr_and_delta_equal_the_numpy_path(key, changes):
    """The tolerances of the module docstring, with a delta's J error from its inverse (``_jacobian_error``)."""
    mech = _design(key, changes)
    names = RRR_DELTA_NAMES + (("spatial_resolution",) if "spatial_resolution" in available_quantities(mech) else ())
    pts = _design_points(key, mech, np.random.default_rng(5))
    fast, ref = _both(mech, pts, names)
    assert fast.computed == ref.computed
    q = np.where(np.isnan(ref.joints), fast.joints, ref.joints)
    margin, allowance = _feasibility_margin(mech, q, pts)
    border = margin <= allowance
    assert not np.any((fast.feasible != ref.feasible) & ~border)
    both = fast.feasible & ref.feasible
    assert both.sum() > 1000
    assert np.all(np.abs(fast.joints[both] - ref.joints[both]) <= 8 * math.pi * EPS)
    assert np.all(np.isnan(fast.joints[~fast.feasible]))
    # Classes: the kernel hands every pose at or near a singular one back, so the labels are numpy's.
    np.testing.assert_array_equal(fast.values["singularity"], ref.values["singularity"])
    regular = both & (ref.values["singularity"] == 0)
    with kernels.use_compiled(False):
        jac = evaluate(mech, pts[regular], ["jacobian"]).values["jacobian"]
    dj = _jacobian_error(mech, q[regular], pts[regular])
    tol = _relative_tolerances(jac, ref.values["condition_number"][regular], dj)
    for name in names:
        a, b = fast.values[name], ref.values[name]
        if name in ("bottleneck", "singularity"):
            np.testing.assert_array_equal(a[~both], b[~both])
            continue
        assert np.array_equal(np.isnan(a), np.isnan(b)) and np.array_equal(np.isinf(a), np.isinf(b)), name
        np.testing.assert_array_equal(a[both & ~regular], b[both & ~regular])     # handed back: numpy's
        finite = np.isfinite(b[regular])
        np.testing.assert_array_equal(a[regular][~finite], b[regular][~finite])
        assert np.all(np.abs(a[regular] - b[regular])[finite] <= (tol[name] * np.abs(b[regular]))[finite]), name
    # A bottleneck moves only where two facets are within the tie rule's reach of each other.
    assert np.mean(fast.values["bottleneck"][both] == ref.values["bottleneck"][both]) > 0.999


@pytest.mark.parametrize("key", ["phantom_premium_15", "novint_falcon"])
@pytest.mark.parametrize("scale", [1e-100, 1e-30, 1e30, 1e100])
def test_rrr_and_delta_far_from_unit_scale_are_numpys_or_handed_back(key, scale):
    """Every length (and the points) scaled: outside ``linalg.SAFE_SCALE`` (2^+-150) J's singular values
    leave the closed forms' safe range and every feasible point is handed back (numpy's numbers
    exactly); at 1e+-30 the kernel computes them."""
    mech = load_preset(key).mechanism
    lengths = (("link1_length", "link2_length", "crank_length") if key.startswith("phantom") else
               ("upper_arm", "parallelogram", "knee_offset", "platform_joint_offset", "platform_offset_u",
                "platform_offset_v", "base_radius", "base_offset_v"))
    scaled = mech.replace(**{name: getattr(mech.params, name) * scale for name in lengths})
    pts = _design_points(key, mech, np.random.default_rng(9), count=5000) * scale
    names = ("condition_number", "isotropic_force", "anisotropic_force", "bottleneck", "singularity")
    fast, ref = _both(scaled, pts, names)
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    assert ref.feasible.sum() > 500
    _, _, _, _, back = kernels.find(scaled, names, DEFAULT_LOADING).run(pts)
    if not SAFE_SCALE[0] < scale < SAFE_SCALE[1]:
        assert np.all(back[ref.feasible])
    else:
        assert np.mean(back[ref.feasible]) < 0.1
    for name in names:
        a, b = fast.values[name], ref.values[name]
        if name in ("bottleneck", "singularity"):
            assert np.mean(a == b) > 0.999
            continue
        assert np.array_equal(np.isinf(a), np.isinf(b)) and np.array_equal(np.isnan(a), np.isnan(b)), name
        finite = np.isfinite(b)
        np.testing.assert_allclose(a[finite], b[finite], rtol=1e-9, atol=0, err_msg=name)


@pytest.mark.parametrize("key", ["phantom_premium_15", "novint_falcon"])
@pytest.mark.parametrize("torque", [1e-300, 1e300])
def test_rrr_and_delta_extreme_torques_are_handed_back_or_scale_exactly(key, torque):
    mech = load_preset(key).mechanism.replace(motor_torques=(torque,) * 3)
    pts = _design_points(key, mech, np.random.default_rng(2), count=2000)
    names = ("isotropic_force", "anisotropic_force", "bottleneck")
    fast, ref = _both(mech, pts, names)
    np.testing.assert_array_equal(fast.feasible, ref.feasible)
    for name in ("isotropic_force", "anisotropic_force"):
        a, b = fast.values[name][ref.feasible], ref.values[name][ref.feasible]
        assert np.array_equal(np.isinf(a), np.isinf(b)) and np.all(a > 0), name
        finite = np.isfinite(b)
        np.testing.assert_allclose(a[finite], b[finite], rtol=64 * EPS * 100, atol=0)


@pytest.mark.parametrize("key", ["phantom_premium_15", "novint_falcon"])
def test_rrr_and_delta_maps_are_the_same_on_one_thread_and_every_thread(key):
    preset = load_preset(key)
    grid = preset.grid if len(preset.grid.axes) == 3 else preset.grid.with_resolution(301)
    names = ("condition_number", "isotropic_force", "anisotropic_force", "inverse_condition_number", "bottleneck",
             "singularity")
    many = compute_map(preset.mechanism, grid, names, threads=True)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        one = compute_map(preset.mechanism, grid, names, threads=True)
    finally:
        numba.set_num_threads(before)
    serial = compute_map(preset.mechanism, grid, names, threads=False)
    with kernels.use_compiled(False):
        ref = compute_map(preset.mechanism, grid, names)
    for other in (one, serial):
        np.testing.assert_array_equal(other.feasible, many.feasible)
        for name in names:
            np.testing.assert_array_equal(other.values[name], many.values[name], err_msg=name)
        assert other.stats == many.stats and other.errors == many.errors and other.gci == many.gci
    np.testing.assert_array_equal(many.feasible, ref.feasible)
    np.testing.assert_array_equal(many.singular, ref.singular)
    for name in names:
        np.testing.assert_array_equal(np.isnan(many.values[name]), np.isnan(ref.values[name]), err_msg=name)
        if name in many.stats:
            a, b = many.stats[name], ref.stats[name]
            assert (a.count, a.singular_points) == (b.count, b.singular_points), name


def test_numba_start_up_skips_scipys_blas_probe_and_blas_still_works():
    """``jit`` loads numba's numpy support without importing ``scipy.linalg`` (0.3 s of start-up); a compiled
    ``np.dot`` still finds the real BLAS, and the stand-in defers to the real module when read."""
    code = textwrap.dedent("""
        import sys
        import numba, numpy as np
        from metrics.kernels import jit
        print("scipy.linalg" in sys.modules, "scipy.linalg.cython_blas" in sys.modules)
        dot = numba.njit(lambda a: np.dot(a, a))
        print(bool(np.all(dot(2.0 * np.eye(3)) == 4.0 * np.eye(3))))
        stand_in = jit._DeferredModule("scipy.linalg.cython_blas")
        sys.modules["scipy.linalg.cython_blas"] = stand_in
        print(len(stand_in.__pyx_capi__) > 0, sys.modules["scipy.linalg.cython_blas"] is not stand_in)
    """)
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "False", "True", "True", "True"]


def test_the_outer_reach_is_the_models_to_the_last_bit():
    """At the five-bar's outer reach ``a3 = l1 + l2`` the kernel's early rejection (no ``hypot``) keeps the
    model's feasible set: points from 64 ulps inside to 4096 outside, along the horizontal through the
    plane (th3 = 0, th0 = 0), with a spread limit so small that the model's last feasible point is a
    few ulps inside the reach: a rejection reaching inside it would show here."""
    for mech in (Inverse3().replace(min_link_spread=1e-12),
                 Inverse3().replace(min_link_spread=1e-12, proximal_length=0.3, distal_length=0.01)):
        p = mech.params
        reach = p.proximal_length + p.distal_length
        steps = np.arange(-64, 4097)
        u = reach * (1.0 + steps * EPS)
        pts = np.stack([u, np.full_like(u, p.plane_offset), np.full_like(u, p.base_height)], axis=-1)
        fast, ref = _both(mech, pts, ("condition_number",))
        assert ref.feasible.any() and not ref.feasible.all()
        assert np.array_equal(fast.feasible, ref.feasible)


@pytest.mark.parametrize("key", ["inverse3_prototype", "phantom_premium_15", "fivebar_singh"])
def test_unfilled_values_are_the_filled_ones_where_feasible(key):
    """``fill=False`` (a map's pass) leaves the value rows of the points that are not feasible as
    they were (and, ``SPARSE_JOINTS``, every joint); everything else is the filled pass's, bit for bit (the
    values where the pass keeps the point), and a streamed map's statistics are the
    kept map's (counts, extremes and their places exactly; the mean, SD and quantiles to their accumulation)."""
    preset = load_preset(key)
    mech = preset.mechanism
    names = ("condition_number", "inverse_condition_number", "isotropic_force", "anisotropic_force",
             "spatial_resolution", "apparent_mass_min", "apparent_mass_max", "isotropic_acceleration")
    if mech.joint_speed_limits() is not None:
        names += ("isotropic_velocity",)
    names = tuple(n for n in names if n in available_quantities(mech))     # (the five-bar has no sensors)
    kernel = kernels.find(mech, names, DEFAULT_LOADING)
    assert kernel.module.SPARSE_VALUES
    pts = preset.grid.with_resolution(201).points(mech.task_names).reshape(-1, mech.task_dim)
    filled = kernel.run(pts)
    sparse = kernel.run(pts, fill=False)
    feasible = filled[0]
    assert np.array_equal(sparse[0], feasible) and 0 < feasible.sum() < feasible.size
    if not getattr(kernel.module, "SPARSE_JOINTS", False):      # else not written: a map reads none
        np.testing.assert_array_equal(sparse[1], filled[1])
    for label in ("bottleneck", "singularity"):
        np.testing.assert_array_equal(sparse[3][label], filled[3][label])
    np.testing.assert_array_equal(sparse[4], filled[4])
    rows = [kernels.COLUMNS.index(n) for n in names]
    kept = feasible & ~filled[4]            # a handed-back point's values are the numpy path's (``evaluate``)
    np.testing.assert_array_equal(sparse[2][rows][:, kept], filled[2][rows][:, kept])
    assert np.all(np.isnan(filled[2][:, ~feasible]))
    grid = preset.grid.with_resolution(301)
    kept = compute_map(mech, grid, names)
    streamed = compute_map(mech, grid, names, keep=False)
    for name in names:
        a, b = streamed.stats[name], kept.stats[name]
        assert (a.count, a.singular_points, a.min, a.max, a.argmin, a.argmax) == (
            b.count, b.singular_points, b.min, b.max, b.argmin, b.argmax), name
        assert a.mean == pytest.approx(b.mean, rel=(math.log2(a.count) + 2) * EPS)
        for f in statistics.QUANTILES:
            assert abs(getattr(a, f) - getattr(b, f)) <= statistics.QUANTILE_REL_ERROR * abs(getattr(b, f))


@pytest.mark.parametrize("design", range(5))
def test_early_limit_decisions_are_the_exact_ones(design):
    """Poses at each joint limit and spread limit, and 1e-16 .. 1e-4 rad either side of it: the Inverse3 pass
    decides the limits of most points from directions and ``cos_h`` (``inverse3._limit_arcs``), rejecting
    without ``atan2``/``acos`` and, without ``fill``, accepting without them too. Without ``fill`` the pass
    must give the filled pass's feasible set, values and hand-backs bit for bit (the filled pass accepts only
    through the angles), and both the numpy model's feasible set away from a bound (``_limit_margin``)."""
    mech = _designs()[design]
    p = mech.params
    rng = np.random.default_rng(90 + design)
    n = 4000
    offsets = 10.0 ** rng.uniform(-16, -4, n) * rng.choice([-1.0, 1.0], n)
    lo, hi = np.array(p.lower_limits), np.array(p.upper_limits)
    mid = 0.5 * (lo + hi)
    poses = []
    for j in range(3):
        for edge in (lo[j], hi[j]):
            q = mid + rng.uniform(-0.5, 0.5, (n, 3)) * (hi - lo) * 0.5
            q[:, j] = edge + offsets
            poses.append(q)
    for spread in (p.min_link_spread, p.max_link_spread):
        q = mid + rng.uniform(-0.5, 0.5, (n, 3)) * (hi - lo) * 0.5
        q[:, 2] = q[:, 1] - (spread + offsets)
        poses.append(q)
    q = np.concatenate(poses)
    x, ok = mech.forward(q)
    pts = x[ok & np.all(np.isfinite(x), axis=-1)]
    kernel = kernels.find(mech, NAMES[:-1], DEFAULT_LOADING)
    filled, sparse = kernel.run(pts), kernel.run(pts, fill=False)
    np.testing.assert_array_equal(sparse[0], filled[0])
    np.testing.assert_array_equal(sparse[4], filled[4])
    kept = filled[0] & ~filled[4]
    assert 1000 < kept.sum() < len(pts)
    rows = [kernels.COLUMNS.index(n) for n in NAMES[:-1]]       # the others are not written without fill
    np.testing.assert_array_equal(sparse[2][rows][:, kept], filled[2][rows][:, kept])
    np.testing.assert_array_equal(sparse[3]["bottleneck"], filled[3]["bottleneck"])
    fast, ref = _both(mech, pts, ("condition_number",))
    with np.errstate(invalid="ignore"):
        qq = np.where(np.isnan(ref.joints), fast.joints, ref.joints)
        border = _limit_margin(mech, qq, pts) <= 8 * math.pi * EPS
    assert not np.any((fast.feasible != ref.feasible) & ~border)
