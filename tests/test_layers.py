"""The package's shape holds by construction: one import name, layers that only import downward.

Layers (docs/DESIGN.md): the core (``dalembert/*.py``) imports none of the others;
``dalembert.reference`` only the core; ``dalembert.cases`` the core and the
reference; ``dalembert.adapters`` the core and the reference (the reference
engine's adapter wraps the reference solver); ``dalembert.reports`` only the
core (it reads stores, never runs anything); ``dalembert.harness`` joins them all.
``dalembert.testing`` (the case contract for case authors, ``check_case``) is a top-level
module but not core: it runs the reference solver, so it is its own layer, allowed the core
and the reference (like the cases it checks), and the harness may use it.
``dalembert.models`` (URDF and MJCF files into scenes) is a layer beside the scene inside ``dalembert/``: it
imports only the core, and the core may not import it; the cases use it (the robot cases).
``dalembert.engine_check`` (the probes of ``dalembert check-engine``) runs adapters: it is allowed the
core, the reference and the adapters; ``dalembert.testing.check_engine`` and the harness use it.
Every import counts, including those inside functions.
"""

import ast
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
with open(os.path.join(ROOT, "pyproject.toml"), "rb") as _fh:
    SETUPTOOLS = tomllib.load(_fh)["tool"]["setuptools"]
LAYERS = ("models", "reference", "cases", "adapters", "reports", "engine_check", "harness", "testing")
# layer -> the layers it may import ("core" is dalembert's own top-level modules)
ALLOWED = {
    "core": {"core"},
    "models": {"core", "models"},
    "reference": {"core", "reference"},
    "cases": {"core", "reference", "cases", "models"},
    "adapters": {"core", "reference", "adapters"},
    "reports": {"core", "reports"},
    "engine_check": {"core", "reference", "adapters", "engine_check"},
    "testing": {"core", "reference", "testing", "engine_check"},
    "harness": {"core", *LAYERS},
}


def _layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else "core"


def _modules():
    """module name -> source path of every first-party module, through the package-dir mapping."""
    out = {}
    for package, folder in SETUPTOOLS["package-dir"].items():
        for here, dirs, files in os.walk(os.path.join(ROOT, folder)):
            dirs[:] = [d for d in dirs if os.path.exists(os.path.join(here, d, "__init__.py"))]
            rel = os.path.relpath(here, os.path.join(ROOT, folder))
            prefix = package if rel == "." else package + "." + rel.replace(os.sep, ".")
            if package == "dalembert" and rel.split(os.sep)[0] in LAYERS:
                continue  # dalembert/harness is its own layer (walked as part of dalembert, named below)
            for f in files:
                if f.endswith(".py"):
                    name = prefix if f == "__init__.py" else f"{prefix}.{f[:-3]}"
                    out[name] = os.path.join(here, f)
    for layer in ("harness", "engine_check", "models"):  # the layers that live inside dalembert/
        top = os.path.join(ROOT, "dalembert", layer)
        for here, dirs, files in os.walk(top):
            dirs[:] = [d for d in dirs if os.path.exists(os.path.join(here, d, "__init__.py"))]
            rel = os.path.relpath(here, top)
            prefix = f"dalembert.{layer}" + ("" if rel == "." else "." + rel.replace(os.sep, "."))
            for f in files:
                if f.endswith(".py"):
                    out[prefix + ("" if f == "__init__.py" else "." + f[:-3])] = os.path.join(here, f)
    return out


MODULES = _modules()


def _imports(module, path):
    """First-party modules imported anywhere in the file (relative imports resolved)."""
    tree = ast.parse(open(path).read(), path)
    package = module if path.endswith("__init__.py") else module.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            found.add(base)
            found |= {f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in MODULES}
    return {m for m in found if m == "dalembert" or m.startswith("dalembert.")}


def test_every_package_is_installed():
    """Each folder with an __init__.py under a mapped folder is in pyproject's package list."""
    packages = {m for m, p in MODULES.items() if p.endswith("__init__.py")}
    assert packages == set(SETUPTOOLS["packages"])


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_point_downward(module):
    layer = _layer(module)
    upward = sorted(m for m in _imports(module, MODULES[module]) if _layer(m) not in ALLOWED[layer])
    assert not upward, f"{module} ({layer}) imports {upward}: allowed layers {sorted(ALLOWED[layer])}"


def test_the_layer_walk_sees_an_upward_import():
    """The checker itself: a core module that imported the reports would be caught."""
    report = "dalembert.harness.commands.report"
    assert "dalembert.reports.render" in _imports(report, MODULES[report])
    assert _layer("dalembert.reports.render") not in ALLOWED["core"]


def test_one_import_name_after_install(tmp_path):
    """The wheel ``pip install .`` would install holds nothing but ``dalembert/`` (no top-level
    ``cases``, ``reports``, ...) and ships the C++ source; in the installed venv, from a directory
    that is not the checkout, ``import cases`` fails and ``import dalembert.cases`` works."""
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".git", ".venv", "results", "build", "*.egg-info",
                                                             "__pycache__", "test-artifacts"))
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(tmp_path / "dist"), str(src)], capture_output=True, text=True)
    assert built.returncode == 0, built.stderr[-2000:]
    (wheel,) = (tmp_path / "dist").iterdir()
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"dalembert"}
    for module in MODULES:
        assert module.replace(".", "/") + ".py" in names or module.replace(".", "/") + "/__init__.py" in names, module
    assert any(n.startswith("dalembert/adapters/") and n.endswith(".cpp") for n in names)
    probe = ("import importlib\n"
             "for name in ('cases', 'reports', 'adapters', 'reference'):\n"
             "    try:\n        importlib.import_module(name)\n    except ModuleNotFoundError:\n        pass\n"
             "    else:\n        raise SystemExit(name + ' imports')\n"
             "import dalembert.cases, dalembert.reports, dalembert.adapters, dalembert.reference\n")
    ran = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True)
    assert ran.returncode == 0, ran.stdout + ran.stderr


# One concept, one module: a module past this many lines is doing more than one job (the rooms the
# renovation split were 555-718 lines, each holding several concepts).
MAX_MODULE_LINES = 500


def test_no_module_is_over_the_line_limit():
    """Every first-party module (tests and benchmarks aside) fits in MAX_MODULE_LINES lines."""
    long = {m: n for m, p in MODULES.items() if (n := sum(1 for _ in open(p))) > MAX_MODULE_LINES}
    assert not long, f"over {MAX_MODULE_LINES} lines — split by concept: {long}"
