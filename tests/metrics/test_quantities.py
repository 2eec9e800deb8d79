"""The quantity graph: ``evaluate`` returns what was asked, computes only what that needs,
and only at feasible points. Headless: numpy only; fixed seeds.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from kinematics import FiveBar, Inverse3
from metrics import anisotropy, bottleneck, columns, conditioning, ellipsoids, isotropy, parallelepiped, quantities
from metrics.quantities import MAP_QUANTITIES, QUANTITIES, available_quantities, closure, evaluate
from metrics.resolution import mechanism_steps

LIMITED = dict(joint_limits=((0.3, 2.6), (-0.4, 2.0)))


def _fivebar_points(rng, shape):
    count = int(np.prod(shape))
    x = np.column_stack([rng.uniform(-0.25, 0.25, count), rng.uniform(-0.2, 0.27, count)])
    return x.reshape(shape + (2,))


def _inverse3_points(rng, shape):
    count = int(np.prod(shape))
    x = np.column_stack([rng.uniform(-0.1, 0.35, count), rng.uniform(-0.1, 0.2, count),
                         rng.uniform(-0.15, 0.5, count)])
    return x.reshape(shape + (3,))


# -- shapes and names ----------------------------------------------------------------------------
@pytest.mark.parametrize("mech, make", [(FiveBar(**LIMITED), _fivebar_points), (Inverse3(), _inverse3_points)])
def test_evaluate_returns_exactly_the_requested_names_with_the_batch_shape(mech, make):
    rng = np.random.default_rng(1)
    x = make(rng, (6, 7))
    names = available_quantities(mech)
    for request in (("condition_number",), ("isotropic_force", "bottleneck"), names):
        ev = evaluate(mech, x, request)
        assert set(ev.values) == set(request)
        for name in request:
            assert ev.values[name].shape == (6, 7), name
        assert ev.feasible.shape == (6, 7) and ev.feasible.dtype == bool
        assert ev.joints.shape == (6, 7, mech.n_joints)
    assert 0 < ev.feasible.sum() < 42
    # A flat batch gives the same values.
    flat = evaluate(mech, x.reshape(-1, mech.task_dim), names)
    for name in names:
        np.testing.assert_array_equal(flat.values[name], ev.values[name].reshape(42), err_msg=name)


def test_available_quantities_depend_on_the_mechanism():
    assert "singularity" in available_quantities(FiveBar())
    assert "singularity" not in available_quantities(Inverse3())
    # The moment capabilities exist only for devices with orientation freedoms.
    # The five-bar models no joint sensors: no resolution quantities either.
    # A bare FiveBar() has no mass model (its preset's estimated bodies give it one): no masses;
    # and no motor speeds: no velocity, until they are given.
    assert set(available_quantities(FiveBar())) == set(MAP_QUANTITIES) - {
        "isotropic_moment", "anisotropic_moment", "spatial_resolution", "angular_resolution",
        "apparent_mass_min", "apparent_mass_max", "mass_condition_number", "isotropic_acceleration", "weight",
        "isotropic_velocity"}
    assert "isotropic_velocity" in available_quantities(FiveBar(motor_speeds=(10.0, 10.0)))
    for name in ("jacobian", "singular_values", "column_norms", "reference_forces"):
        assert name not in MAP_QUANTITIES


def test_unknown_quantity_raises_naming_it():
    with pytest.raises(ValueError, match="unknown quantity 'stiffness'"):
        evaluate(FiveBar(), np.zeros((3, 2)), ["condition_number", "stiffness"])
    with pytest.raises(ValueError, match="unknown quantity 'singularity' for Inverse3"):
        evaluate(Inverse3(), np.zeros((3, 3)), ["singularity"])
    with pytest.raises(ValueError, match=r"points must have shape \(\.\.\., 3\)"):
        evaluate(Inverse3(), np.zeros((3, 2)), ["condition_number"])


# -- laziness ------------------------------------------------------------------------------------
POLYTOPE_NODES = ("column_norms", "isotropic_force", "bottleneck", "reference_forces", "anisotropic_force",
                  "force_ellipsoid_min_radius")


def _forbid(*args, **kwargs):
    raise AssertionError("polytope code was called for a request that does not need it")


@pytest.mark.parametrize("mech", [FiveBar(), Inverse3()])
def test_condition_number_alone_never_touches_polytope_code(monkeypatch, mech):
    for module, fn in ((parallelepiped, "reference_forces"), (columns, "column_norms"),
                       (isotropy, "isotropic_force"), (anisotropy, "anisotropic_force"),
                       (isotropy, "facet_distances"), (bottleneck, "bottleneck_actuator"),
                       (parallelepiped, "polytope_vertices")):
        monkeypatch.setattr(module, fn, _forbid)
    monkeypatch.setattr(ellipsoids, "force_ellipsoid_min_radius", _forbid)
    for name in POLYTOPE_NODES:
        monkeypatch.setitem(QUANTITIES, name, dataclasses.replace(QUANTITIES[name], compute=_forbid))
    rng = np.random.default_rng(2)
    x = _fivebar_points(rng, (50,)) if isinstance(mech, FiveBar) else _inverse3_points(rng, (50,))
    ev = evaluate(mech, x, ["condition_number"])
    assert ev.computed == ("joints", "jacobian", "singular_values", "condition_number")
    assert list(ev.values) == ["condition_number"]
    assert np.isfinite(ev.values["condition_number"][ev.feasible]).all()
    # The guard is real: asking for a polytope quantity now fails.
    with pytest.raises(AssertionError, match="polytope code was called"):
        evaluate(mech, x, ["isotropic_force"])


def test_closure_lists_inputs_first_and_nothing_else():
    assert closure(["condition_number"]) == ["jacobian", "singular_values", "condition_number"]
    order = closure(["anisotropic_force"])
    assert set(order) == {"jacobian", "reference_forces", "anisotropic_force"}
    assert order.index("jacobian") < order.index("reference_forces") < order.index("anisotropic_force")
    order = closure(["isotropic_force", "bottleneck", "condition_number"])
    assert set(order) == {"jacobian", "column_norms", "isotropic_force", "bottleneck", "singular_values",
                          "condition_number"}
    assert len(order) == len(set(order))
    for name in order:
        for dep in QUANTITIES[name].needs:
            if dep not in ("pose", "joints"):
                assert order.index(dep) < order.index(name)
    assert closure(["singularity"]) == ["singularity"]


def test_computed_lists_every_touched_node():
    ev = evaluate(Inverse3(), _inverse3_points(np.random.default_rng(3), (20,)), ["isotropic_force"])
    assert ev.computed == ("joints", "jacobian", "column_norms", "isotropic_force")


# -- only feasible points ----------------------------------------------------------------------
class RecordingFiveBar(FiveBar):
    """Records the batch size of every Jacobian call (the model itself is immutable)."""

    calls: list[int] = []

    def jacobian(self, q, x=None):
        RecordingFiveBar.calls.append(int(np.shape(q)[0]))
        return super().jacobian(q, x)


class RecordingInverse3(Inverse3):
    calls: list[int] = []

    def jacobian(self, q, x=None):
        RecordingInverse3.calls.append(int(np.shape(q)[0]))
        return super().jacobian(q, x)


@pytest.mark.parametrize("cls, make", [(RecordingFiveBar, _fivebar_points), (RecordingInverse3, _inverse3_points)])
def test_quantities_are_computed_only_at_feasible_points(cls, make):
    mech = cls(**LIMITED) if cls is RecordingFiveBar else cls()
    x = make(np.random.default_rng(4), (400,))
    q, reachable = mech.inverse(x)
    feasible = reachable.copy()
    feasible[reachable] = mech.feasible(q[reachable])
    # The sample has all three kinds of point: unreachable, reachable but infeasible, feasible.
    assert (~reachable).sum() > 10 and (reachable & ~feasible).sum() > 10 and feasible.sum() > 10
    cls.calls.clear()
    ev = evaluate(mech, x, available_quantities(mech))
    assert cls.calls == [int(feasible.sum())]
    np.testing.assert_array_equal(ev.feasible, feasible)
    for name in available_quantities(mech):
        values = ev.values[name]
        if QUANTITIES[name].categorical:
            assert np.issubdtype(values.dtype, np.integer), name
            assert np.all(values[~feasible] == -1), name
            # Feasible points hold a class, an actuator, or a bottleneck tie / shared code; never -1.
            assert np.all(values[feasible] != -1), name
        else:
            assert np.all(np.isnan(values[~feasible])), name
            assert not np.any(np.isnan(values[feasible])), name
    assert np.all(np.isnan(ev.joints[~feasible]))
    np.testing.assert_array_equal(ev.joints[feasible], q[feasible])


@pytest.mark.parametrize("mech, make", [(FiveBar(**LIMITED), _fivebar_points), (Inverse3(), _inverse3_points),
                                        (FiveBar(working_mode="-+", assembly_mode="down"), _fivebar_points)])
def test_values_equal_the_metric_functions_at_the_inverse_kinematics_pose(mech, make):
    x = make(np.random.default_rng(5), (300,))
    ev = evaluate(mech, x, available_quantities(mech))
    f = ev.feasible
    q, xf = ev.joints[f], x[f]
    jac = mech.jacobian(q, xf) if isinstance(mech, FiveBar) else mech.jacobian(q)
    t = mech.torque_limits()
    expected = {
        "condition_number": conditioning.condition_number(jac),
        "inverse_condition_number": 1.0 / conditioning.condition_number(jac),
        "manipulability": conditioning.manipulability(jac),
        "isotropic_force": isotropy.isotropic_force(jac, torque_limits=t),
        "bottleneck": bottleneck.bottleneck_actuator(jac, torque_limits=t),
        "anisotropic_force": anisotropy.anisotropic_force(jac, torque_limits=t),
        "force_ellipsoid_min_radius": ellipsoids.force_ellipsoid_min_radius(jac, torque_limits=t),
    }
    if isinstance(mech, FiveBar):
        expected["singularity"] = mech.singularity(q, xf)
    steps = mechanism_steps(mech)
    if steps is not None:                                            # sensors modelled (the Inverse3)
        expected["spatial_resolution"] = np.max(np.linalg.norm(jac, axis=-2) * steps, axis=-1)
    assert set(expected) == set(available_quantities(mech))
    for name, value in expected.items():
        np.testing.assert_allclose(ev.values[name][f], value, rtol=1e-13, err_msg=name)


def test_fivebar_jacobian_is_taken_at_the_requested_pose():
    """An IK pose in the other assembly mode than the model's still gets its own Jacobian."""
    mech = FiveBar()                                           # "+-", "up"
    x = np.array([[0.02, -0.05], [0.0, 0.15]])                 # below the base line: "+-" assembles down
    ev = evaluate(mech, x, ["condition_number", "isotropic_force"])
    assert ev.feasible.all()
    q = ev.joints
    down = mech.replace(assembly_mode="down")
    np.testing.assert_allclose(down.forward(q[0])[0], x[0], atol=1e-14)
    cond_true = conditioning.condition_number(mech.jacobian(q, x))
    np.testing.assert_allclose(ev.values["condition_number"], cond_true, rtol=1e-13)
    iso_true = isotropy.isotropic_force(mech.jacobian(q, x), torque_limits=mech.torque_limits())
    np.testing.assert_allclose(ev.values["isotropic_force"], iso_true, rtol=1e-13)
    # ... which differs from the Jacobian of the configured assembly at the same joints.
    iso_wrong = isotropy.isotropic_force(mech.jacobian(q[0]), torque_limits=mech.torque_limits())
    assert not np.isclose(iso_wrong, iso_true[0], rtol=1e-3)


def test_all_infeasible_points_give_nan_without_error():
    mech = Inverse3()
    x = np.full((4, 5, 3), 2.0)                                # far out of reach
    ev = evaluate(mech, x, available_quantities(mech))
    assert not ev.feasible.any()
    for name in available_quantities(mech):
        assert ev.values[name].shape == (4, 5)
        if QUANTITIES[name].categorical:
            assert np.all(ev.values[name] == -1)
        else:
            assert np.all(np.isnan(ev.values[name]))


def test_requested_names_are_not_duplicated_or_reordered_by_dependencies():
    x = _inverse3_points(np.random.default_rng(6), (30,))
    ev = evaluate(Inverse3(), x, ["isotropic_force", "condition_number"])
    assert list(ev.values) == ["isotropic_force", "condition_number"]
    assert quantities.CORE_QUANTITIES == ("condition_number", "anisotropic_force", "isotropic_force")
