"""The torque set validated once (``metrics.torque_box.TorqueSet``) and passed down as it is.

Every force-set function takes a ``TorqueSet`` as its ``torque_limits``; with one it must give
the same bits as with the plain ``torque_limits`` / ``torque_min`` / ``torque_bias`` arrays it
stands for (the same operations on the same numbers, so equality is exact, not approximate).
A map and a pose build the set once from their ``Loading`` and the graph's nodes read it.
"""
from __future__ import annotations

import numpy as np
import pytest

from metrics import anisotropic_force, bottleneck_actuator, facet_distances, isotropic_force
from metrics.dynamics import isotropic_acceleration
from metrics.ellipsoids import force_ellipsoid, force_ellipsoid_min_radius
from metrics.loading import Loading
from metrics.parallelepiped import polytope_centre, polytope_vertices, reference_forces
from metrics.quantities import QUANTITIES, evaluate
from metrics.torque_box import TorqueSet, torque_range, torque_set
from metrics.zonotopes import zonotope, zonotope_vertices
from resources import load_preset

RNG = np.random.default_rng(24)
JAC = RNG.normal(size=(6, 3, 3))
T = np.array([1.0, 2.0, 0.5])
#: Plain keyword sets: symmetric, a bias (off-centre), a centred minimum, an asymmetric minimum.
CASES = [
    {},
    {"torque_bias": RNG.normal(scale=0.3, size=(6, 3))},
    {"torque_min": -T},
    {"torque_min": np.array([-0.5, -2.0, 0.0]), "torque_bias": np.array([0.1, 0.0, -0.2])},
]


def _same(a, b) -> bool:
    return np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("case", range(len(CASES)))
def test_a_torque_set_gives_the_bits_of_the_plain_arrays(case):
    kwargs = CASES[case]
    box = TorqueSet.of(T, n=3, **kwargs)
    for fn in (facet_distances, isotropic_force, bottleneck_actuator, anisotropic_force, polytope_vertices,
               polytope_centre, reference_forces):
        assert _same(fn(JAC, torque_limits=box), fn(JAC, torque_limits=T, **kwargs)), fn.__name__
    gen = JAC[:, :2, :]
    z_box, z_plain = zonotope(gen, torque_limits=box), zonotope(gen, torque_limits=T, **kwargs)
    assert _same(z_box.offsets, z_plain.offsets) and _same(z_box.normals, z_plain.normals)
    assert _same(zonotope_vertices(gen, torque_limits=box), zonotope_vertices(gen, torque_limits=T, **kwargs))
    lam = np.einsum("kij,klj->kil", JAC, JAC) + np.eye(3)
    if "torque_min" not in kwargs:
        assert _same(isotropic_acceleration(JAC, lam, torque_limits=box),
                     isotropic_acceleration(JAC, lam, torque_limits=T, **kwargs))
    # The ellipsoids are of the rated limits, whatever shifts the set.
    assert _same(force_ellipsoid_min_radius(JAC, torque_limits=box), force_ellipsoid_min_radius(JAC, torque_limits=T))
    assert _same(force_ellipsoid(JAC, torque_limits=box).radii, force_ellipsoid(JAC, torque_limits=T).radii)


def test_the_set_holds_the_range_torque_range_gives():
    b = np.array([[0.5, -0.25, 0.0]])
    box = TorqueSet.of(T, n=3, torque_bias=b)
    lo, hi = torque_range(T, n=3, torque_bias=b)
    assert _same(box.lower, lo) and _same(box.upper, hi)
    assert _same(box.nearer, T - np.abs(b)) and _same(box.per_unit.bias, b / T)
    assert box.unbiased.bias is None and box.unbiased.limits is box.limits
    assert box.with_bias(None).centred_limits is box.limits


def test_a_set_is_taken_as_it_is_and_plain_limits_are_checked_naming_the_argument():
    box = TorqueSet.of(T, n=3)
    assert torque_set(box, n=3) is box
    with pytest.raises(ValueError, match="torque_min and torque_bias are part of a TorqueSet"):
        isotropic_force(JAC, torque_limits=box, torque_bias=np.zeros(3))
    with pytest.raises(ValueError, match="torque_limits must be positive and finite"):
        isotropic_force(JAC, torque_limits=[1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="torque_bias must be finite"):
        isotropic_force(JAC, torque_limits=T, torque_bias=[np.nan, 0.0, 0.0])


def test_a_loaded_map_s_nodes_give_the_numbers_of_the_plain_arrays():
    mech = load_preset("inverse3_prototype").mechanism
    grid = load_preset("inverse3_prototype").grid.with_resolution(5)
    points = grid.points(tuple(mech.task_names)).reshape(-1, mech.task_dim)
    loading = Loading.mounted("upright")
    names = ["isotropic_force", "anisotropic_force", "bottleneck"]
    result = evaluate(mech, points, names, loading=loading)
    feasible = result.feasible
    assert feasible.any()
    bias = evaluate(mech, points, ["torque_bias"], loading=loading).values["torque_bias"][feasible]
    jac = evaluate(mech, points, ["jacobian"]).values["jacobian"][feasible]
    t = loading.torque_limits(mech)
    assert _same(result.values["isotropic_force"][feasible], isotropic_force(jac, torque_limits=t, torque_bias=bias))
    assert _same(result.values["anisotropic_force"][feasible],
                 anisotropic_force(jac, torque_limits=t, torque_bias=bias))
    assert _same(result.values["bottleneck"][feasible], bottleneck_actuator(jac, torque_limits=t, torque_bias=bias))


def test_nodes_run_on_values_built_by_hand_get_the_loading_s_set():
    mech = load_preset("inverse3_prototype").mechanism
    points = load_preset("inverse3_prototype").grid.with_resolution(5).points(tuple(mech.task_names))
    loading = Loading.mounted("upright")
    entry = evaluate(mech, points, ["isotropic_force", "torque_bias", "column_norms"], loading=loading)
    ok = entry.feasible
    values = {"joints": entry.joints[ok], "loading": loading, "torque_bias": entry.values["torque_bias"][ok],
              "column_norms": entry.values["column_norms"][ok]}
    assert _same(QUANTITIES["isotropic_force"].run(values, mech), entry.values["isotropic_force"][ok])
