"""One engine run as the engine tests take it: prepared, run, read back, audited."""

import importlib.util
import os

from dalembert import Settings, invariants
from dalembert.adapters import adapter_names, adapter_path, get_adapter
from dalembert.case import make_case

__all__ = ["run_with_audit", "run_case", "installed"]


def run_with_audit(scene, times, integrator, dt, engine="mujoco", **options):
    """``(trajectory, audit)`` of ``engine`` on ``scene`` sampled at ``times`` (s), with ``integrator`` at the
    fixed step ``dt`` (s) and the engine ``options``."""
    adapter = get_adapter(engine)
    prepared = adapter.prepare(scene, times, Settings(integrator, dt=dt, options=options))
    out = adapter.run(prepared)
    return out.trajectory, adapter.audit(prepared, out)


def run_case(engine, name, settings, **params):
    """``(case, prepared, outcome, drifts)``: case ``name`` (with ``params``) checked, refused by nothing, prepared
    and run once by ``engine`` with ``settings``; ``drifts`` holds its conserved quantities' drifts and its
    metrics (``dalembert.metrics``) as the harness stores them."""
    adapter = get_adapter(engine)
    case = make_case(name, **params)
    adapter.check(case.scene, case.times, settings)
    assert adapter.unsupported(case.scene, settings) is None
    prepared = adapter.prepare(case.scene, case.times, settings)
    outcome = adapter.run(prepared)
    drifts = invariants.summary(case.scene, outcome.trajectory, case.conserved, case.invariants).drifts
    return case, prepared, outcome, drifts


def installed(engine):
    """Whether ``engine``'s package is installed here (its adapter's ``version`` does not raise ImportError): an
    optional engine outside ``all`` (MuJoCo Warp) is absent from a fresh ``make test``."""
    try:
        get_adapter(engine).version()
    except ImportError:
        return False
    return True


def real_engines():
    """Every registered engine but the suite's own test adapters (classes defined in tests/: a test module
    registers them when it is imported, so which of them a process holds depends on what xdist gave it)."""
    here = os.path.dirname(os.path.abspath(__file__))
    out = []
    for name in adapter_names():
        spec = importlib.util.find_spec(adapter_path(name).partition(":")[0])
        origin = os.path.abspath(spec.origin) if spec and spec.origin else ""
        if os.path.dirname(origin) != here:
            out.append(name)
    return out
