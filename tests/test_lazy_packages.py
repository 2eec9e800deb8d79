"""The packages' public names load on first use: importing a package imports none of its models or maps.

``kinematics``, ``metrics`` and ``resources`` give their public names through PEP 562
``__getattr__`` (and ``kinematics.registry.MECHANISMS`` its classes on look-up), so that a
command imports the modules it uses, not every one a package lists. Checked in fresh
interpreters: other tests import everything into this process.
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def fresh(code: str):
    """The JSON value ``code`` prints last, run in a fresh interpreter."""
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("package", ["kinematics", "metrics", "resources"])
def test_every_public_name_is_the_object_of_its_module(package):
    """Each name of ``__all__`` resolves (``from package import *`` too), to the object its module holds."""
    code = (f"import json, importlib, {package} as p\n"
            f"ns = {{}}; exec('from {package} import *', ns)\n"
            "for name in p.__all__:\n"
            "    value = getattr(p, name)\n"
            "    assert ns[name] is value, name\n"
            "    mod = getattr(value, '__module__', None) or ''\n"
            "    if mod.startswith(p.__name__ + '.'):\n"
            "        assert getattr(importlib.import_module(mod), getattr(value, '__name__', name), value) is value\n"
            "print(json.dumps({'names': sorted(p.__all__), 'dir': sorted(set(p.__all__) - set(dir(p)))}))")
    out = fresh(code)
    assert out["dir"] == [] and len(out["names"]) == len(set(out["names"])) >= 4


def test_an_unknown_name_is_an_attribute_error():
    import kinematics
    import metrics
    import resources

    for package in (kinematics, metrics, resources):
        with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
            package.no_such_name  # noqa: B018


def test_importing_a_package_imports_no_model_and_no_map():
    loaded = fresh("import json, sys, kinematics, metrics, resources\n"
                   "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in "
                   "('kinematics', 'metrics', 'resources'))))")
    # resources reads presets on import of its schema: the registry, the grid and base, no model.
    models = {"kinematics.inverse3", "kinematics.fivebar", "kinematics.twin_pantograph", "kinematics.stewart",
              "kinematics.delta", "kinematics.serial_rrr", "kinematics.inoue"}
    assert not set(loaded) & models, sorted(set(loaded) & models)
    assert not [m for m in loaded if m.startswith("metrics.")], loaded


def test_the_registry_imports_only_the_model_looked_up():
    out = fresh("import json, sys\n"
                "from kinematics.registry import MECHANISMS, kind_of, mechanism_class\n"
                "keys = list(MECHANISMS); known = 'delta' in MECHANISMS and [] not in MECHANISMS\n"
                "kind = kind_of(mechanism_class('fivebar')())\n"
                "models = sorted(m for m in sys.modules if m in {'kinematics.' + k for k in keys})\n"
                "print(json.dumps({'keys': keys, 'known': known, 'kind': kind, 'models': models}))")
    assert out == {"keys": ["inverse3", "fivebar", "twin_pantograph", "stewart", "delta", "serial_rrr", "inoue"],
                   "known": True, "kind": "fivebar", "models": ["kinematics.fivebar"]}


def test_the_registry_is_the_mapping_it_was():
    from kinematics.registry import MECHANISMS, kind_of, mechanism_class

    classes = dict(MECHANISMS)
    assert len(classes) == len(MECHANISMS) == 7
    for kind, cls in classes.items():
        assert mechanism_class(kind) is cls and MECHANISMS[kind] is cls and kind_of(cls()) == kind
    with pytest.raises(KeyError):
        MECHANISMS["nope"]
    with pytest.raises(ValueError, match="must be one of"):
        mechanism_class(["unhashable"])

    class Sub(classes["fivebar"]):
        pass

    with pytest.raises(ValueError, match="registered kinds"):
        kind_of(Sub())
