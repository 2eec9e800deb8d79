"""Study files are read by ``resources`` (kinematics only) into plain data; ``metrics.design`` builds them."""
from __future__ import annotations

import subprocess
import sys

import pytest

from resources import StudyError, StudyFile, list_studies, load_study, study_file


def test_shipped_studies_load_as_plain_data():
    keys = list_studies()
    assert "fivebar_table1" in keys and keys == sorted(keys)
    for key in keys:
        spec = load_study(key)
        assert isinstance(spec, StudyFile) and spec.key == key and spec.n_designs >= 1


def test_unknown_study_names_the_shipped_ones():
    with pytest.raises(StudyError, match=r"unknown study 'nope'; shipped: .*fivebar_table1"):
        load_study("nope")


def test_the_objective_vocabulary_is_said_once_in_metrics_design():
    """resources reads [objective] as typed values; the kinds and their rules are metrics.design's."""
    from metrics import design
    assert not any(hasattr(study_file, name) for name in ("OBJECTIVES", "DIRECTIONS", "MASS_OBJECTIVES"))
    assert "min_isotropic_force" in design.OBJECTIVES
    entry = study_file.ObjectiveEntry(kind="fastest", direction=None, infeasible=None, top_k=5)
    assert entry.kind == "fastest"          # read as given; build_study refuses it (tests/metrics/test_studies.py)


def test_reading_a_study_imports_no_metrics():
    code = ("import sys, resources; resources.load_study('twin_pantograph_distance'); "
            "print(sorted(m for m in sys.modules if m == 'metrics' or m.startswith('metrics.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
