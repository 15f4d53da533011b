"""``check_adapter``: the adapter contract (``dalembert.adapters``) run on registered cases."""

from __future__ import annotations

from dalembert.adapters.base import Prepared
from dalembert.adapters.registry import get_adapter

__all__ = ["check_adapter"]


# The adaptive integrators' tolerance in the contract: it checks behaviour (sampling, repeatability, the
# audit), not accuracy, so it takes the default matrix's loosest rtol (``harness.matrix``), the cheapest a
# user runs (DOP853 on andrews_squeezer: 4 s per run at 1e-8 on 2 cores, ~2.5 s at 1e-6).
CONTRACT_TOL = 1e-6


def check_adapter(name, cases=None, settings=None, integrators=None):
    """Run the contract on every registered case ``name`` supports; returns a list of problems.

    Parameters
    ----------
    name : str — engine name
    cases : iterable of Case, optional — default: every registered case (defaults)
    settings : callable(integrator name, IntegratorSpec) -> Settings, optional —
        default: dt = the sample interval for fixed-step, rtol = atol = ``CONTRACT_TOL`` otherwise
    integrators : iterable of str, optional — default: every integrator of the engine
    """
    import numpy as np

    from dalembert.case import load_cases
    from dalembert.settings import Settings
    from dalembert.trajectory import Trajectory

    adapter = get_adapter(name)
    unknown = sorted(set(integrators or ()) - set(adapter.integrators))
    if unknown:
        raise ValueError(f"integrators: {name} has no {', '.join(unknown)} — known: {', '.join(adapter.integrators)}")
    problems = [f"{name}: option {o!r} is taken by an integrator but not declared in {type(adapter).__name__}.options"
                for o in sorted({o for spec in adapter.integrators.values() for o in spec.options} - set(adapter.options))]
    adapter.version()
    if cases is None:
        cases = [factory() for _, factory in load_cases().items()]
    for case in cases:
        for integ, spec in adapter.integrators.items():
            if integrators is not None and integ not in integrators:
                continue
            if settings is not None:
                s = settings(integ, spec)
            elif spec.fixed_step:
                s = Settings(integ, dt=float(case.times[1] - case.times[0]))
            else:
                s = Settings(integ, rtol=CONTRACT_TOL, atol=CONTRACT_TOL)
            where = f"{name} {case.name} {s.label()}"
            adapter.check(case.scene, case.times, s)
            reason, before = adapter.unsupported(case.scene, s), adapter.unsupported_before_build(case.scene, s)
            if before and before != reason:  # the matrix lists the one, a run would have stored the other
                problems.append(f"{where}: unsupported_before_build gives {before!r}, unsupported {reason!r}: the part "
                                "known before the build must be unsupported's own words")
            if reason:
                continue
            if not isinstance(adapter.describe(case.scene, s), str):
                problems.append(f"{where}: describe() must return text")
            prepared = adapter.prepare(case.scene, case.times, s)
            if not isinstance(prepared, Prepared):
                problems.append(f"{where}: prepare() must return a Prepared (dalembert.adapters.base)")
            first, second = adapter.run(prepared), adapter.run(prepared)
            traj = first.trajectory
            if not isinstance(traj, Trajectory):
                problems.append(f"{where}: run() must return a Trajectory")
                continue
            if not np.array_equal(traj.t, case.times):
                problems.append(f"{where}: not sampled at exactly the case's times")
            if set(traj.bodies) != {b.name for b in case.scene.bodies}:
                problems.append(f"{where}: bodies {sorted(traj.bodies)} != scene's")
            for bname, b in traj.bodies.items():
                if not np.array_equal(b.quaternion, second.trajectory.bodies[bname].quaternion,
                                      equal_nan=True):
                    problems.append(f"{where}: a repeated run gave different results")
            if not (first.wall_s >= 0.0 and first.n_steps >= 0 and first.n_rhs >= 0):
                problems.append(f"{where}: cost figures must be non-negative")
            audit = adapter.audit(prepared, first)
            if "gravity" not in audit:
                problems.append(f"{where}: the audit must report the gravity vector")
            elif not np.allclose(audit["gravity"], case.scene.gravity, rtol=0, atol=0):
                problems.append(f"{where}: engine gravity {audit['gravity']} != scene {case.scene.gravity}")
    return problems
