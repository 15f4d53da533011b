"""One engine run as the engine tests take it: prepared, run, read back, audited."""

from dalembert import Settings
from dalembert.adapters import get_adapter

__all__ = ["run_with_audit"]


def run_with_audit(scene, times, integrator, dt, engine="mujoco", **options):
    """``(trajectory, audit)`` of ``engine`` on ``scene`` sampled at ``times`` (s), with ``integrator`` at the
    fixed step ``dt`` (s) and the engine ``options``."""
    adapter = get_adapter(engine)
    prepared = adapter.prepare(scene, times, Settings(integrator, dt=dt, options=options))
    out = adapter.run(prepared)
    return out.trajectory, adapter.audit(prepared, out)
