"""Design studies: the TOML schema, the design-vectorised five-bar, and exactness of every search
(culling == brute force, also split into chunks, on local processes and on a dask LocalCluster)."""
from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest

from kinematics import FiveBar
from metrics import design
from metrics.design import build_study, count_brute_force, count_search, evaluator_for, run_study
from metrics.design.batch import fivebar_batch, isotropic_force_fast
from metrics.design.evaluator_adapters import table
from metrics.quantities import evaluate
from resources import StudyError, study_schema

STUDIES = Path(__file__).resolve().parents[2] / "resources" / "studies"

SMALL_FIVEBAR = """
name = "small five-bar"
[mechanism]
preset = "fivebar_singh"
[grid]
proximal = { min = 60.0, max = 120.0, step = 20.0 }
distal = [110.0, 130.0, 150.0, 170.0]
half_base = { min = 10.0, max = 70.0, step = 15.0 }
[workspace]
kind = "grid"
axes = ["x", "y"]
lower = [-50.0, 110.0]
upper = [50.0, 170.0]
resolution = [8, 6]
[objective]
kind = "min_isotropic_force"
infeasible = "{infeasible}"
top_k = {top_k}
"""


def parse_study_text(text: str, source: str, key: str = ""):
    """Read (resources) and build (metrics.design) a study from TOML text."""
    return build_study(study_schema.parse_study_text(text, source, key))


def read_study_file(path):
    return build_study(study_schema.read_study_file(path))


def study(text: str, source: str = "test.toml"):
    return parse_study_text(textwrap.dedent(text), source, Path(source).stem)


def small(infeasible="fail", top_k=4):
    return study(SMALL_FIVEBAR.replace("{infeasible}", infeasible).replace("{top_k}", str(top_k)))


def same_top(a, b):
    assert np.array_equal(a.top_designs, b.top_designs)
    assert np.array_equal(a.top_values, b.top_values)


def exact_values(st):
    """Brute-force values of every design (objective units), for checking the records."""
    ev = evaluator_for(st)
    out = ev(np.arange(st.n_designs), np.arange(ev.n_samples))
    form = ev.form
    if form == "sum":
        return out.sum(axis=1)
    if form == "ratio":
        a, b = out
        bad = np.isnan(a) | np.isnan(b)
        amin = np.where(bad, np.inf, a).min(axis=1)
        bmax = np.where(bad, 0.0, b).max(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = np.where((amin == 0) | (bmax == np.inf), 0.0, amin / bmax)
        if st.objective.infeasible == "fail":
            v[bad.any(axis=1)] = -np.inf
        v[bad.all(axis=1)] = -np.inf
        return v
    bad = np.isnan(out)
    v = np.where(bad, np.inf, out).min(axis=1)
    if st.objective.infeasible == "fail":
        v[bad.any(axis=1)] = -np.inf
    v[bad.all(axis=1)] = -np.inf
    return v


def check_records(st, res):
    """Every record is the design's exact value, or a valid bound of it."""
    truth = exact_values(st)
    rec = res.records
    assert np.array_equal(rec["design"], np.arange(st.n_designs))
    ex = rec["exact"]
    assert np.array_equal(rec["value"][ex], truth[ex])
    assert np.all(rec["samples"][ex] == res.n_samples)
    if st.objective.form == "sum":
        assert np.all(rec["value"][~ex] <= truth[~ex])       # partial counts: lower bounds
    else:
        assert np.all(rec["value"][~ex] >= truth[~ex])       # upper bounds of the value
    # the ranking is the brute-force ranking of the true values
    sign = -1.0 if st.objective.form == "sum" else 1.0
    order = np.lexsort((np.arange(truth.size), -sign * truth))[: len(res.top_designs)]
    assert np.array_equal(res.top_designs, order)
    assert np.array_equal(res.top_values, truth[order])


# -- the schema ---------------------------------------------------------------------------------
BAD = [
    ('colour = "red"\n' + SMALL_FIVEBAR, "colour", "is not a study key"),
    (SMALL_FIVEBAR.replace("proximal = {", "wheels = {"), "grid.wheels", "not a numeric parameter"),
    (SMALL_FIVEBAR.replace("step = 20.0", "step = 25.0"), "grid.proximal.step", "whole steps"),
    (SMALL_FIVEBAR.replace("step = 20.0", "step = -20.0"), "grid.proximal.step", "positive"),
    (SMALL_FIVEBAR.replace("distal = [110.0", "distal = [-110.0"), "grid.distal", "out of range"),
    (SMALL_FIVEBAR.replace("distal = [110.0, 130.0", "distal = [130.0, 130.0"), "grid.distal", "repeat"),
    (SMALL_FIVEBAR.replace('kind = "grid"', 'kind = "cloud"'), "workspace.kind", "one of"),
    (SMALL_FIVEBAR.replace("resolution = [8, 6]", "resolution = [8]"), "workspace.resolution", "list of 2"),
    (SMALL_FIVEBAR.replace('axes = ["x", "y"]', 'axes = ["x", "q"]'), "workspace.axes", "distinct names"),
    (SMALL_FIVEBAR.replace('kind = "min_isotropic_force"', 'kind = "fastest"'), "objective.kind", "one of"),
    (SMALL_FIVEBAR.replace('infeasible = "{infeasible}"', 'direction = "min"'), "objective.direction", "'max'"),
    (SMALL_FIVEBAR.replace('kind = "min_isotropic_force"', 'kind = "count_condition_above"')
     .replace('infeasible = "{infeasible}"', ""), "objective.threshold", "is missing"),
    (SMALL_FIVEBAR.replace('infeasible = "{infeasible}"', 'infeasible = "fail"\nS_T = [1.0, 1.0]'),
     "objective.S_T", "gii only"),
    (SMALL_FIVEBAR.replace('kind = "min_isotropic_force"', 'kind = "gii"')
     .replace('infeasible = "{infeasible}"', 'S_T = [1.0, 2.0, 3.0]'), "objective.S_T", "2 positive numbers"),
    (SMALL_FIVEBAR.replace('preset = "fivebar_singh"', 'preset = "no_such_device"'), "mechanism.preset",
     "cannot be loaded"),
    (SMALL_FIVEBAR.replace('preset = "fivebar_singh"', 'kind = "fivebar"\nparameters = { distal = -3.0 }'),
     "mechanism.parameters.distal", "out of range"),
    (SMALL_FIVEBAR + '[report]\nreference = { proximal = 60.0 }\n', "report.reference", "'distal' is missing"),
    (SMALL_FIVEBAR + '[report]\nreference = { proximal = 60.0, distal = 110.0, half_base = 10.0 }\n'
                     'smallest = "colour"\n', "report.smallest", "one of"),
    (SMALL_FIVEBAR + '[series]\nkey = "workspace.tilt"\nvalues = [1.0]\n', "series.key", "workspace.centre"),
    (SMALL_FIVEBAR.replace("[grid]", "[grid]\ngear_ratios = { min = 1.0, max = 2.0, step = 1.0 }"),
     "grid.gear_ratios", "name an entry"),
    (SMALL_FIVEBAR.replace("[grid]", "[grid]\ngear_ratios.theta_9 = [1.0, 2.0]"), "grid.gear_ratios.theta_9",
     "expected one of theta_1, theta_2"),
]


def test_a_sampling_workspace_needs_the_planar_link_lengths_it_samples():
    """metrics.sweeps samples (x, y) from proximal, distal and half_base: the Inverse3 has neither."""
    text = SMALL_FIVEBAR.replace('preset = "fivebar_singh"', 'preset = "inverse3_prototype"')
    text = text[:text.index("[grid]")] + '[grid]\nproximal_length = [140.0, 150.0]\n' + text[text.index("[workspace]"):]
    text = text[:text.index("[workspace]")] + '[workspace]\nkind = "sampling"\nname = "normalised"\n' \
        + text[text.index("[objective]"):]
    with pytest.raises(StudyError) as err:
        study(text.replace("{infeasible}", "fail").replace("{top_k}", "3"), "my_study.toml")
    message = str(err.value)
    assert "'workspace.kind'" in message and "proximal, distal, half_base" in message and "inverse3" in message


@pytest.mark.parametrize("text, key, words", BAD, ids=[f"{b[1]}-{i}" for i, b in enumerate(BAD)])
def test_bad_study_names_file_and_key(text, key, words):
    with pytest.raises(StudyError) as err:
        study(text.replace("{infeasible}", "fail").replace("{top_k}", "3"), "my_study.toml")
    message = str(err.value)
    assert message.startswith("study 'my_study.toml': key ")
    assert f"'{key}'" in message and words in message, message


def test_not_toml_and_missing_tables():
    with pytest.raises(StudyError, match="study 'x.toml': is not valid TOML"):
        parse_study_text("name = ", "x.toml")
    with pytest.raises(StudyError, match="key 'workspace' is missing"):
        parse_study_text('[mechanism]\nkind = "fivebar"\n[grid]\nproximal = [90.0]\n[objective]\n'
                         'kind = "gii"\n', "x.toml")


def test_grid_values_design_ids_and_units():
    st = small()
    assert st.shape == (4, 4, 5) and st.n_designs == 80 and st.n_samples == 48
    assert st.parameters[0].display == (60.0, 80.0, 100.0, 120.0)
    assert st.parameters[0].si == (0.06, 0.08, 0.1, 0.12)
    assert st.parameters[0].unit == "mm"
    d = st.design_id({"proximal": 80.0, "distal": 150.0, "half_base": 40.0})
    assert d == 1 * 20 + 2 * 5 + 2                       # first parameter slowest (C order)
    assert st.design_mechanism(d).params.proximal == 0.08
    fields = st.field_values([d])
    assert fields["distal"][0] == 0.15 and fields["half_base"][0] == 0.04
    # decimal steps are exact as typed
    g = study(SMALL_FIVEBAR.replace("{infeasible}", "fail").replace("{top_k}", "3")
              .replace("[grid]", "[grid]\ngear_ratios.theta_1 = { min = 6.875, max = 7.0, step = 0.025 }"))
    assert g.parameters[0].display == (6.875, 6.9, 6.925, 6.95, 6.975, 7.0)
    assert g.field_values([g.n_designs - 1])["gear_ratios"][0].tolist() == [7.0, 10.0]


def test_shipped_studies_parse_with_their_sizes():
    keys = sorted(p.stem for p in STUDIES.glob("*.toml"))
    assert keys == ["fivebar_large", "fivebar_table1", "inoue_table5", "inverse3_gear_ratio",
                    "inverse3_gear_ratio_mass", "stewart_table4", "twin_pantograph_distance",
                    "twin_pantograph_sensor", "twin_pantograph_table3", "twin_pantograph_table7"]
    t1 = read_study_file(STUDIES / "fivebar_table1.toml")
    assert (t1.n_designs, t1.n_samples) == (60, 27000)
    big = read_study_file(STUDIES / "fivebar_large.toml")
    assert big.n_designs >= 10**6 and big.n_samples >= 10**3
    tp = read_study_file(STUDIES / "twin_pantograph_distance.toml")
    runs = tp.runs()
    assert [r.series_value for r in runs] == [150.0, 200.0, 250.0, 300.0, 350.0, 400.0]
    assert runs[0].n_samples == 27 * 18                  # positions x orientations (N = 2 at 45 deg)
    z = runs[2].workspace.points[:, 2]
    assert np.isclose(z.min(), 0.2) and np.isclose(z.max(), 0.3)
    assert runs[0].objective.s_t == (1.0, 1.0, 1.5, 0.036, 0.039)
    g = read_study_file(STUDIES / "inverse3_gear_ratio.toml")
    assert g.workspace.size == 250 * 250 and g.report.smallest == "gear_ratios.theta_0"


# -- the design-vectorised five-bar ---------------------------------------------------------------
@pytest.mark.parametrize("mode", ["+-", "-+", "++", "--"])
def test_fivebar_batch_equals_evaluate(mode):
    rng = np.random.default_rng(7)
    k = 25
    a1, a2, a3 = rng.uniform(0.05, 0.2, k), rng.uniform(0.05, 0.25, k), rng.uniform(0.005, 0.08, k)
    t = rng.uniform(0.05, 5.0, (k, 2))
    pts = np.stack([rng.uniform(-0.3, 0.3, 800), rng.uniform(-0.1, 0.4, 800)], -1)
    names = ("isotropic_force", "condition_number", "column_norms")
    batch = fivebar_batch(a1[:, None], a2[:, None], a3[:, None], pts[None], quantities=names,
                          torque_limits=t[:, None, :], working_mode=mode)
    fast = isotropic_force_fast(a1[:, None], a2[:, None], a3[:, None], pts[None, :, 0], pts[None, :, 1],
                                t[:, 0:1], t[:, 1:2], mode)
    reachable = 0
    for i in range(k):
        mech = FiveBar(proximal=a1[i], distal=a2[i], half_base=a3[i], motor_torques=tuple(t[i]),
                       gear_ratios=(1.0, 1.0), working_mode=mode)
        ev = evaluate(mech, pts, names)
        assert np.array_equal(ev.feasible, batch.feasible[i])
        reachable += ev.feasible.sum()
        for q in names:
            ours, ref = batch.values[q][i], ev.values[q]
            assert np.array_equal(np.isnan(ours), np.isnan(ref)) and np.array_equal(np.isinf(ours), np.isinf(ref))
            f = np.isfinite(ref)
            np.testing.assert_allclose(ours[f], ref[f], rtol=1e-12, atol=0)
        np.testing.assert_array_equal(fast[i], batch.values["isotropic_force"][i])
    assert reachable > 0.2 * k * len(pts)                # a real test: many reachable points


def test_fivebar_batch_validates_and_handles_singular_poses():
    with pytest.raises(ValueError, match="proximal"):
        fivebar_batch(-0.1, 0.15, 0.03, [[0.0, 0.15]])
    with pytest.raises(ValueError, match="torque_limits"):
        fivebar_batch(0.1, 0.15, 0.03, [[0.0, 0.15]], quantities=("isotropic_force",))
    # C at distance a1 + a2 from base joint 0 (leg 0 stretched): an inverse singularity, a zero
    # column of J, a facet at infinity; the same numbers as evaluate()
    a1, a2, a3 = 0.1, 0.1, 0.05
    x = np.array([[-a3 + 0.2, 0.0]])
    out = fivebar_batch(a1, a2, a3, x, quantities=("isotropic_force", "condition_number"),
                        torque_limits=[1.0, 1.0])
    mech = FiveBar(proximal=a1, distal=a2, half_base=a3, motor_torques=(1.0, 1.0))
    ev = evaluate(mech, x, ("isotropic_force", "condition_number"))
    assert out.feasible[0] == ev.feasible[0]
    for q in ("isotropic_force", "condition_number"):
        np.testing.assert_array_equal(out.values[q], ev.values[q])


# -- exactness: the count (sum form) ---------------------------------------------------------------
def test_count_search_equals_brute_force_on_random_tables():
    rng = np.random.default_rng(3)
    for trial in range(150):
        D, S = int(rng.integers(1, 40)), int(rng.integers(1, 120))
        p = rng.uniform(0.02, 0.6, (D, 1))
        f = (rng.random((D, S)) < p).astype(float)
        if trial % 3 == 0:
            f[rng.integers(0, D, 3)] = f[0]              # exact ties
        ev = table(f)
        k = int(rng.integers(1, 6))
        ref = count_brute_force(ev, D, S, top_k=k)
        res = count_search(ev, D, S, top_k=k, first_chunk=int(rng.integers(1, 20)))
        same_top(res, ref)
        assert res.evaluations <= D * S
        # a subset with a floor from the rest, merged: still the global top K
        if D >= 4:
            ids = np.arange(D)
            a, b = ids[: D // 2], ids[D // 2:]
            ra = count_search(ev, a, S, top_k=k)
            floor = ra.kth if len(ra.top_designs) == k else None
            rb = count_search(ev, b, S, top_k=k, floor=floor, initial_samples=ra.probes)
            same_top(design.merge_top_k([ra, rb], top_k=k), ref)


def test_count_evaluator_must_return_indicators():
    with pytest.raises(ValueError, match="0 or 1"):
        count_search(table(np.full((3, 4), 0.5)), 3, 4)


def test_table1_study_equals_sweep_and_brute_force():
    from scripts.paper_data import table1_sweep

    st = read_study_file(STUDIES / "fivebar_table1.toml")
    res = run_study(st)
    brute = run_study(st, method="brute_force")
    same_top(res, brute)
    sweep = table1_sweep("normalised_arcs")
    assert np.array_equal(brute.records["value"], sweep.counts)       # the same 60 counts
    assert res.top()[0] == {"rank": 1, "design": 27, "proximal": 100.0, "distal": 150.0, "half_base": 30.0,
                            "value": 454.0}                            # paper 002's winner
    assert res.top()[1]["value"] == 456.0 and res.evaluations < 0.5 * res.brute_force_evaluations
    check_records(st, res)
    split = run_study(st, chunks=7)
    same_top(split, brute)
    check_records(st, split)


# -- exactness: max-min forms on the study evaluators ----------------------------------------------
@pytest.mark.parametrize("infeasible", ["fail", "skip"])
def test_fivebar_study_culling_equals_brute_force(infeasible):
    st = small(infeasible, top_k=5)
    brute = run_study(st, method="brute_force")
    assert np.isfinite(brute.top_values).all()
    ev = evaluator_for(st)
    assert np.isnan(ev(np.arange(st.n_designs), np.arange(st.n_samples))).any()   # unreachable samples
    if infeasible == "fail":
        assert (exact_values(st) == -np.inf).any()       # designs that cannot reach everything
    for chunks in (1, 3, 80):
        res = run_study(st, chunks=chunks)
        same_top(res, brute)
        check_records(st, res)


def test_torque_only_study_ties_and_report():
    text = """
    [mechanism]
    preset = "inverse3_prototype"
    [grid]
    gear_ratios.theta_0 = { min = 6.0, max = 16.0, step = 0.25 }
    [workspace]
    kind = "preset_map"
    resolution = [40, 40]
    [objective]
    kind = "min_isotropic_force"
    infeasible = "skip"
    top_k = 6
    [report]
    reference = { "gear_ratios.theta_0" = 13.75 }
    tolerance = 1e-3
    smallest = "gear_ratios.theta_0"
    checks = [{ label = "+60 %", "gear_ratios.theta_0" = 11.0 }, { label = "off grid", "gear_ratios.theta_0" = 20.0 }]
    """
    st = study(text)
    ev = evaluator_for(st)
    assert type(ev).__name__ == "TorqueOnly" and ev.n_samples < 40 * 40
    brute = run_study(st, method="brute_force", with_report=False)
    res = run_study(st, chunks=4)
    same_top(res, brute)
    check_records(st, res)
    truth = exact_values(st)
    # the plateau: several designs share the best value exactly; ties go to the smaller g1
    assert np.sum(truth == truth.max()) >= 6 and np.all(res.top_values == truth.max())
    assert np.all(np.diff(res.top_designs) == 1)
    rep = res.report
    g1 = np.asarray(st.parameters[0].display)
    ref = truth[st.design_id({"gear_ratios.theta_0": 13.75})]
    assert rep.reference_value == ref and rep.target == ref - 1e-3 * ref
    reaching = g1[truth >= rep.target]
    assert rep.smallest_design == {"gear_ratios.theta_0": reaching.min()}
    assert rep.checks[0]["value"] == truth[st.design_id({"gear_ratios.theta_0": 11.0})]
    assert rep.checks[0]["reaches"] is False                   # +60 % is not enough
    assert rep.checks[1]["value"] == ref                       # beyond the plateau: no change


def test_gii_study_on_the_fivebar_and_the_twin_pantograph():
    fivebar = study("""
    [mechanism]
    kind = "fivebar"
    [grid]
    proximal = [80.0, 100.0, 120.0]
    distal = [130.0, 150.0]
    half_base = [20.0, 40.0]
    gear_ratios.theta_1 = [1.0, 2.0]
    [workspace]
    kind = "grid"
    axes = ["x", "y"]
    lower = [-40.0, 120.0]
    upper = [40.0, 180.0]
    resolution = [5, 4]
    [objective]
    kind = "gii"
    S_T = [1.0, 1.0]
    top_k = 4
    """)
    brute = run_study(fivebar, method="brute_force")
    assert np.all((brute.top_values > 0) & (brute.top_values <= 1))
    res = run_study(fivebar, chunks=3)
    same_top(res, brute)
    check_records(fivebar, res)
    # the GII matches metrics.gii on the optimum, computed independently
    from metrics import gii as gii_mod
    mech = fivebar.design_mechanism(res.design)
    pts = fivebar.workspace.points
    ev = evaluate(mech, pts, ("jacobian",))
    ref = gii_mod.gii(ev.values["jacobian"], mech.torque_limits(), [1.0, 1.0], ev.feasible)
    assert res.value == pytest.approx(ref.value, rel=1e-12)

    pen = study("""
    [mechanism]
    kind = "twin_pantograph"
    [grid]
    upper_arm = [150.0, 175.0]
    forearm = [200.0, 225.0]
    Q1 = { targets = ["motor_torques.q1", "motor_torques.q4"], values = [0.12, 0.16] }
    [workspace]
    kind = "grid"
    axes = ["x", "y", "z"]
    lower = [0.0, 0.0, -40.0]
    upper = [60.0, 40.0, 40.0]
    resolution = [2, 2, 2]
    centre = { z = 250.0 }
    [workspace.orientations]
    tip_bound = 45.0
    rings = 1
    [objective]
    kind = "gii"
    S_T = "human_hand"
    top_k = 3
    """)
    assert pen.n_samples == 8 * 6 and pen.objective.frame == "end_effector"
    assert pen.field_values([7])["motor_torques"][0].tolist()[:4] == [0.16, 0.1, 0.1, 0.16]
    brute = run_study(pen, method="brute_force")
    res = run_study(pen, chunks=2)
    same_top(res, brute)
    check_records(pen, res)
    assert 0 < res.value < 1


def test_report_smallest_with_count_objective():
    st = study("""
    [mechanism]
    kind = "fivebar"
    [grid]
    proximal = [90.0, 100.0, 110.0]
    distal = [130.0, 140.0, 150.0]
    [workspace]
    kind = "sampling"
    name = "normalised_arcs"
    [objective]
    kind = "count_condition_above"
    threshold = 5.0
    [report]
    reference = { proximal = 100.0, distal = 150.0 }
    tolerance = 0.05
    smallest = "distal"
    """.replace('[workspace]', '[mechanism.parameters]\nhalf_base = 30.0\n[workspace]'))
    res = run_study(st)
    truth = exact_values(st)
    rep = res.report
    assert rep.reference_value == truth[st.design_id({"proximal": 100.0, "distal": 150.0})]
    ok = truth <= rep.target
    disp = st.design_display(np.arange(st.n_designs))
    want = disp["distal"][ok].min()
    assert rep.smallest_design["distal"] == want
    best = min((truth[i], i) for i in np.flatnonzero(ok & (disp["distal"] == want)))
    assert rep.smallest_value == best[0]


# -- split across processes and a dask cluster ------------------------------------------------------
def test_local_processes_equal_single_process():
    st = small("fail", top_k=5)
    single = run_study(st)
    par = run_study(st, workers=2, chunks=6)
    assert par.engine == "processes" and par.workers == 2
    same_top(par, single)
    check_records(st, par)


def test_dask_local_cluster_equals_single_process():
    distributed = pytest.importorskip("distributed")
    st = read_study_file(STUDIES / "fivebar_table1.toml")
    single = run_study(st)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        res = run_study(st, client=client, chunks=5)
        fail = run_study(small("fail", top_k=3), client=client, chunks=4)
    assert res.engine == "dask" and res.workers == 2
    same_top(res, single)
    check_records(st, res)
    same_top(fail, run_study(small("fail", top_k=3), method="brute_force"))


def test_large_study_design_space_and_evaluator():
    big = read_study_file(STUDIES / "fivebar_large.toml")
    ev = evaluator_for(big)
    assert type(ev).__name__ == "FiveBarBatch"
    rng = np.random.default_rng(11)
    ids = rng.integers(0, big.n_designs, 6)
    block = ev(ids, np.arange(ev.n_samples))
    for row, d in zip(block, ids):
        mech = big.design_mechanism(int(d))
        ref = evaluate(mech, big.workspace.points, ("isotropic_force",)).values["isotropic_force"]
        np.testing.assert_array_equal(np.isnan(row), np.isnan(ref))
        np.testing.assert_allclose(row[~np.isnan(ref)], ref[~np.isnan(ref)], rtol=1e-12)
    chunks = design.plan_chunks(big.n_designs, 16)
    joined = np.sort(np.concatenate(chunks))
    assert len(chunks) == 17 and np.array_equal(joined, np.arange(big.n_designs))


def test_points_workspace_positions_and_whole_poses():
    base = """
    [mechanism]
    kind = "twin_pantograph"
    [grid]
    upper_arm = [150.0, 175.0]
    [workspace]
    kind = "points"
    {points}
    [objective]
    kind = "gii"
    S_T = "human_hand"
    """
    poses = study(base.replace("{points}", "points = [[0.0, 0.0, 250.0, 0.0, 0.0], [10.0, 0.0, 240.0, 30.0, 0.0]]"))
    np.testing.assert_allclose(poses.workspace.points[1], [0.01, 0.0, 0.24, np.radians(30.0), 0.0])
    sampled = study(base.replace("{points}", "points = [[0.0, 0.0, 250.0]]\ncentre = { z = 10.0 }\n"
                                             "[workspace.orientations]\ntip_bound = 30.0\nrings = 1"))
    assert sampled.n_samples == 7 and np.allclose(sampled.workspace.points[:, 2], 0.26)   # K_r = 1 + 6 (eq. 16)
    with pytest.raises(StudyError, match="key 'workspace.points' needs a list of 5"):
        study(base.replace("{points}", "points = [[0.0, 0.0, 250.0]]"))
    res = run_study(poses)
    same_top(res, run_study(poses, method="brute_force"))


def test_redundant_actuation_isotropic_force_uses_the_zonotope():
    st = study("""
    [mechanism]
    kind = "twin_pantograph"
    [grid]
    Q1 = { targets = ["motor_torques.q1", "motor_torques.q4"], values = [0.1, 0.16, 0.3] }
    [workspace]
    kind = "points"
    points = [[0.0, 0.0, 250.0, 0.0, 0.0], [20.0, 10.0, 230.0, 20.0, -10.0]]
    [objective]
    kind = "min_isotropic_force"
    top_k = 2
    """)
    ev = evaluator_for(st)
    assert type(ev).__name__ == "Generic"                     # not TorqueOnly: the force set is a zonotope
    res = run_study(st)
    same_top(res, run_study(st, method="brute_force"))
    mech = st.design_mechanism(res.design)
    ref = evaluate(mech, st.workspace.points, ("isotropic_force",)).values["isotropic_force"]
    assert res.value == ref.min()


# -- issue 7, section 6 --------------------------------------------------------------------
@pytest.mark.parametrize("designs, chunks", [(60, 60), (60, 64), (9, 9), (8, 8), (100_000, 64), (70_000, 1)])
def test_plan_chunks_partitions_the_designs_without_empty_chunks(designs, chunks):
    """Before: 60 designs in 60 chunks after a 7-design warm-up left empty chunks, which crashed
    the search (``optimize fivebar_table1 --workers 16``)."""
    parts = design.plan_chunks(designs, chunks)
    assert all(p.size > 0 for p in parts)
    assert np.array_equal(np.sort(np.concatenate(parts)), np.arange(designs))


def test_a_range_of_two_billion_values_is_refused_before_it_is_made():
    """Before: 2e9 values fit under MAX_DESIGNS and parsing hung building them."""
    text = SMALL_FIVEBAR.replace("{infeasible}", "fail").replace("{top_k}", "4")
    start = text.index("[grid]")
    end = text.index("[workspace]")
    grid = '[grid]\nproximal = { min = 90.0, max = 110.0, step = 0.00000001 }\n'
    with pytest.raises(StudyError, match=r"key 'grid'.*2,000,000,001 designs.*coarser"):
        study(text[:start] + grid + text[end:])


def test_a_study_that_is_not_utf8_names_its_file(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes('name = "K\u00f6rper"\n'.encode("latin-1"))
    with pytest.raises(StudyError, match=r"latin1\.toml.*not UTF-8.*0xf6"):
        read_study_file(path)
