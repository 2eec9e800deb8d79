"""How the compiled kernels load from numba's cache (``metrics.kernels.jit``): without numba's registries.

Each test runs fresh Python processes, as a command starts: what is imported, and whether a function came
from the cache, are per process. The reference for the values is the same kernel loaded through numba's own
refresh (``QUICK_LOAD`` off), which must give the same numbers bit for bit: the same machine code runs.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from metrics.kernels import jit

ROOT = Path(__file__).resolve().parents[2]

# One Inverse3 evaluation through the compiled kernel; what the process imported, and whether the
# kernel's builds came from the cache. ``QUICK`` False decorates the kernels as ``jit`` does for a numba
# version the quick load was not checked against (not by changing numba's version: its cache index is
# keyed on it, and the kernels would compile again).
KERNEL_RUN = """
import json, sys
from metrics.kernels import jit
if not {quick}:
    jit.QUICK_LOAD = False
    jit._numpy_support_without_blas_probe()
import numpy as np
from kinematics import Inverse3
from metrics.kernels import inverse3
from metrics.quantities import evaluate
pts = np.array([[0.2, 0.0223, 0.25], [0.15, 0.0223, 0.3], [0.05, 0.0223, 0.4]])
ev = evaluate(Inverse3(), pts, ["isotropic_force", "condition_number"])
hits = sum(sum(run.stats.cache_hits.values()) for run in (inverse3.run_serial, inverse3.run_parallel))
print(json.dumps({{"quick": jit.QUICK_LOAD, "hits": hits, "arraymath": "numba.np.arraymath" in sys.modules,
                  "scipy.linalg": "scipy.linalg" in sys.modules,
                  "values": {{k: [float(x).hex() for x in v] for k, v in ev.values.items()}}}}))
"""


def _run(code: str, env: dict | None = None) -> dict:
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=900,
                         env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})})
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not jit.QUICK_LOAD, reason="numba version the quick load was not checked against")
def test_a_cached_kernel_loads_without_numbas_registries_and_gives_the_same_numbers():
    """A kernel found in the cache loads without ``numba.np.arraymath`` (nor scipy's BLAS): numba's registries
    are not refreshed. Loaded through numba's refresh instead, it gives the same values, bit for bit."""
    _run(KERNEL_RUN.format(quick=True))                 # compiles into the cache if it is not there yet
    quick = _run(KERNEL_RUN.format(quick=True))
    numba_own = _run(KERNEL_RUN.format(quick=False))
    assert quick["quick"] and not numba_own["quick"]
    assert quick["hits"] >= 1 and numba_own["hits"] >= 1
    assert not quick["arraymath"] and not quick["scipy.linalg"]
    assert numba_own["arraymath"] and not numba_own["scipy.linalg"]       # refreshed, without the BLAS probe
    assert quick["values"] == numba_own["values"]


@pytest.mark.skipif(not jit.QUICK_LOAD, reason="numba version the quick load was not checked against")
def test_a_function_missing_from_the_cache_compiles_then_loads(tmp_path):
    """A ``jit`` function not in the cache is compiled by numba (its refresh, numpy's support without the BLAS
    probe) and saved; the next process loads it, scipy's BLAS still not imported, and both give the same number."""
    (tmp_path / "summed.py").write_text(textwrap.dedent("""
        import numpy as np
        from metrics.kernels.jit import jit

        @jit(allocates=True)
        def summed(a):
            return np.sum(a * a) + a.max()
    """))
    code = textwrap.dedent(f"""
        import json, sys
        sys.path.insert(0, {str(tmp_path)!r})
        import numpy as np
        from summed import summed
        value = summed(np.arange(5.0))
        print(json.dumps({{"value": value, "hits": sum(summed.stats.cache_hits.values()),
                          "misses": sum(summed.stats.cache_misses.values()),
                          "arraymath": "numba.np.arraymath" in sys.modules,
                          "scipy.linalg": "scipy.linalg" in sys.modules}}))
    """)
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    compiled, loaded = _run(code, env), _run(code, env)
    assert (compiled["misses"], compiled["hits"], loaded["misses"], loaded["hits"]) == (1, 0, 0, 1)
    assert compiled["arraymath"] and not compiled["scipy.linalg"]
    # ``np.sum``'s code comes with its environment, which imports ``numba.np.arraymath`` as it loads: without
    # its BLAS probe all the same.
    assert not loaded["scipy.linalg"]
    assert compiled["value"] == loaded["value"] == 34.0


# After ``runtime.warm`` (run.sh's install step), every shipped device's map of every quantity it offers
# and of the statistics' quantities, gravity off and on: the compiled functions each dispatcher holds,
# before and after the maps.
WARM_THEN_MAPS = """
import json, sys
import numba
from metrics import runtime
{before}
runtime.warm()
from metrics.loading import Loading
from metrics.quantities import STATS_QUANTITIES, available_quantities
from metrics.workspace import compute_map
from resources import list_presets, load_preset

def builds():
    return {{f"{{name}}.{{attr}}": [str(sig) for sig in value.overloads]
             for name, module in list(sys.modules.items()) if name.startswith("metrics.kernels.")
             for attr, value in vars(module).items() if isinstance(value, numba.core.registry.CPUDispatcher)}}

warmed = builds()
for name in list_presets():
    preset = load_preset(name)
    offered = available_quantities(preset.mechanism)
    for loading in (Loading(), Loading(gravity=(0.0, 0.0, -9.80665), mounting="upright")):
        # Every quantity (the numpy path where a family's kernel lacks one), and the statistics' (its kernel).
        for request in (offered, [q for q in STATS_QUANTITIES if q in offered]):
            compute_map(preset.mechanism, preset.grid.with_resolution(6), request, loading=loading)
after = builds()
print(json.dumps({{k: v for k, v in after.items() if v != warmed.get(k, [])}}))
"""


def test_a_map_after_the_install_steps_warm_up_builds_and_loads_nothing_new():
    """``runtime.warm`` loads every version of every compiled function a map runs, so the first map after an
    install compiles nothing (the issue's cold start). Before: the grid points' fill (not in ``warm``) and a
    facets radius with a read-only offsets array (a trivial broadcast) were built by the first map."""
    assert _run(WARM_THEN_MAPS.format(before="")) == {}


def test_the_warm_up_check_can_fail():
    """The same check sees a version ``warm`` left out (here the grid points' fill, skipped)."""
    skipped = "from metrics import kernels\nkernels._load_points = lambda: None"
    new = _run(WARM_THEN_MAPS.format(before=skipped))
    assert list(new) == ["metrics.kernels.points.fill"]
