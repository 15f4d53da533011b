"""The engine-free reference solver: Newton-Euler, Kane (d'Alembert), integrators
and closed forms. Imports no engine."""

from dalembert.reference.solver import FORMULATIONS, simulate, truth_settings

__all__ = ["FORMULATIONS", "simulate", "truth", "truth_settings"]


def truth(case):
    """The case's truth trajectory at its sample times.

    The closed form where the case has one (``case.exact``), else the reference
    solver with ``truth_settings(case.scene)``. A scene with loops gets its
    self-stresses beside (``loops.reaction_modes``): reactions are judged modulo them.
    """
    from dataclasses import replace

    from dalembert.reference.loops import reaction_modes

    traj = case.exact(case.times) if case.exact is not None else simulate(case.scene, case.times,
                                                                            truth_settings(case.scene))[0]
    if case.scene.loops:
        traj = replace(traj, extras={**traj.extras, **reaction_modes(case.scene, traj)})
    return traj
