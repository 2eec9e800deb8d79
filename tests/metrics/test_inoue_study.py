"""A design study can name the Inoue platform (kind "inoue") and grid over its Table V parameters:
a 2 x 2 study over l2, l3 (and one with eq. 18's Q1 pair) runs, culling equals brute force, and
the optimum's GII equals metrics.gii computed independently (paper 001 eq. 11, end-effector frame)."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

from kinematics import InouePlatform
from kinematics.rotations import rotation_matrix
from metrics import gii as gii_mod
from metrics.design import build_study, run_study
from resources import study_schema

STUDY = """
name = "Inoue l2 x l3"
[mechanism]
kind = "inoue"
[grid]
upper_arm = [150.0, 170.0]                   # l2, mm
forearm = [230.0, 250.0]                     # l3, mm
{extra}
[workspace]
kind = "grid"
axes = ["x", "y", "z"]
lower = [0.0, -40.0, -40.0]
upper = [60.0, 40.0, 40.0]
resolution = [2, 2, 2]
centre = {{ z = 250.0 }}
[workspace.orientations]
tip_bound = 30.0
rings = 1
[objective]
kind = "gii"
S_T = "human_hand"
top_k = 2
"""


def _study(extra=""):
    text = textwrap.dedent(STUDY.format(extra=extra))
    return build_study(study_schema.parse_study_text(text, "inoue_study.toml", "inoue_study"))


def test_a_2_by_2_study_over_inoue_lengths_runs_and_culling_equals_brute_force():
    st = _study()
    assert isinstance(st.mechanism, InouePlatform) and st.n_designs == 4
    assert st.objective.frame == "end_effector" and len(st.objective.s_t) == 6
    brute = run_study(st, method="brute_force")
    res = run_study(st, chunks=2)
    assert np.array_equal(res.top_designs, brute.top_designs)
    assert np.array_equal(res.top_values, brute.top_values)
    assert 0 < res.value < 1
    # The optimum's GII, independently: force map at every sample, rows in the platform frame.
    mech = st.design_mechanism(res.design)
    pts = st.workspace.points
    q, ok = mech.inverse(pts)
    feas = ok & mech.feasible(q, pts)
    assert feas.all()                                   # infeasible = "fail" would have said so
    a = mech.force_map(q, pts)
    a = gii_mod.rotate_task_rows(a, rotation_matrix(pts[..., 3:6]))
    ref = gii_mod.gii(a, mech.torque_limits(), st.objective.s_t, feas, kind="force_map")
    assert res.value == pytest.approx(ref.value, rel=1e-12)


def test_a_study_varies_eq_18s_q1_pair_through_the_motor_torques():
    st = _study('Q1 = { targets = ["motor_torques.q3", "motor_torques.q6"], values = [0.05, 0.1] }')
    assert st.n_designs == 8
    scales = sorted({round(st.design_mechanism(d).actuator_scales()[0], 12) for d in range(st.n_designs)})
    assert scales == [0.5, 1.0]                          # Q1 = q3 / q1 with q1 = 0.1 N m
    res = run_study(st)
    assert np.array_equal(res.top_designs, run_study(st, method="brute_force").top_designs)


def test_a_study_grids_table_v_angles_in_degrees():
    st = _study("platform_pair_angle = [160.0, 170.0]          # eta2, deg")
    etas = sorted({st.design_mechanism(d).params.platform_pair_angle for d in range(st.n_designs)})
    assert etas == pytest.approx(np.radians([160.0, 170.0]), rel=1e-15)
