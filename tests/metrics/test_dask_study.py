"""A Twin-Pantograph study on a ``dask.distributed`` ``LocalCluster`` of worker processes gives
the same ranking, values and exactly evaluated designs' records as the single-process run,
and brute force's ranking (reduced Table VII, ``tests/metrics/test_twin_batch.py``)."""
from __future__ import annotations

import numpy as np
import pytest
from test_twin_batch import reduced  # the reduced Table VII study

from metrics.design import run_study

distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install "
                                                        "'isoforce[dask]'): the Dask path cannot be tested")


@pytest.fixture(scope="module")
def client():
    # Worker processes, as `isoforce optimize --dask` starts them: the study is pickled and
    # scattered to them, the chunks run there.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as c:
        yield c


def test_twin_study_on_a_local_cluster_equals_the_local_run(client):
    study = reduced()
    single = run_study(study, with_report=False)
    brute = run_study(study, method="brute_force", with_report=False)
    for chunks in (None, 6):
        res = run_study(study, client=client, chunks=chunks, with_report=False)
        assert res.engine == "dask" and res.workers == 2
        np.testing.assert_array_equal(res.top_designs, single.top_designs)
        np.testing.assert_array_equal(res.top_values, single.top_values)
        np.testing.assert_array_equal(res.top_designs, brute.top_designs)
        np.testing.assert_array_equal(res.top_values, brute.top_values)
        # every design the cluster evaluated exactly has brute force's value, to the bit
        exact = res.records["exact"]
        assert exact.any()
        ids = res.records["design"][exact]
        cluster_values = res.records["value"][exact]
        brute_values = brute.records["value"][np.searchsorted(brute.records["design"], ids)]
        np.testing.assert_array_equal(cluster_values, brute_values)
