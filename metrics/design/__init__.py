"""Design studies: an exact search for the best designs of a mechanism over a parameter grid.

A study file (TOML, read and validated by ``resources.load_study``) names the mechanism, the
parameter grid, the workspace and the objective; ``build_study`` makes the searchable
``Study`` and ``run_study`` finds the best designs exactly, on one process, local processes
or a Dask cluster.

==================  =====================================================================
module              what it answers
==================  =====================================================================
``study``           what a study is (``Study``, ``GridParameter``, ``Workspace``, ``Objective``)
``build``           a ``Study`` from a validated file (samples, SI values, memory checks)
``evaluators``      how designs are evaluated (``make_evaluator``, ``evaluator_for``)
``batch``           five-bar designs broadcast against points (``fivebar_batch``)
``mass``            the apparent-mass bound and force per apparent mass (``ApparentMass``)
``ranking``         search results and their order (``SearchResult``, ``TopK``, ``merge_top_k``)
``culling``         the max-min searches (``culling_search``, ``brute_force``)
``evaluator_adapters``  evaluators from plain functions and tables (``per_design``, ``table``)
``count``           the count search beside it (``count_search``, ``count_brute_force``)
``records``         what every design ended with, the result, the [report] answers
``pools``           where chunks run (local processes, Dask)
``runner``          how the search runs (``run_study``, ``search_chunk``, ``plan_chunks``)
==================  =====================================================================
"""
from .build import build_study
from .count import count_brute_force, count_search
from .culling import brute_force, culling_search
from .evaluators import Evaluator, evaluator_for, make_evaluator
from .pools import dask_threads, process_pool, stop_process_pool
from .ranking import SearchResult, TopK, merge_top_k, ranking
from .records import ReportResult, StudyResult, first_reaching, study_report
from .runner import default_chunks, plan_chunks, run_study, search_chunk
from .study import BOUND_MEANING, DIRECTIONS, METHODS, OBJECTIVES, UNITS, GridParameter, Objective, Study, Workspace

__all__ = ["BOUND_MEANING", "DIRECTIONS", "METHODS", "OBJECTIVES", "UNITS", "Evaluator", "GridParameter",
           "Objective", "ReportResult", "SearchResult", "Study", "StudyResult", "TopK", "Workspace",
           "brute_force", "build_study", "count_brute_force", "count_search", "culling_search", "dask_threads",
           "default_chunks", "evaluator_for", "first_reaching", "make_evaluator", "merge_top_k", "plan_chunks",
           "process_pool", "ranking", "run_study", "search_chunk", "stop_process_pool", "study_report"]
