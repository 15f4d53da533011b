"""The engine-free reference solver: Newton-Euler, Kane (d'Alembert), integrators
and closed forms. Imports no engine."""

from dalembert.reference.solver import FORMULATIONS, simulate, truth_settings

__all__ = ["FORMULATIONS", "simulate", "truth", "truth_settings"]


def truth(case):
    """The case's truth trajectory at its sample times.

    The closed form where the case has one (``case.exact``), else the reference
    solver with ``truth_settings(case.scene)``.
    """
    if case.exact is not None:
        return case.exact(case.times)
    return simulate(case.scene, case.times, truth_settings(case.scene))[0]
