"""The reference solver's entry point: ``simulate(scene, times, settings)``."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from dalembert.reference.generalized import Kane
from dalembert.reference.integrators import INTEGRATORS, DOP853, check_settings, first_order
from dalembert.reference.loops import ClosedLoops
from dalembert.reference.newton_euler import NewtonEuler
from dalembert.reference.planar import PlanarChain, why_not

__all__ = ["FORMULATIONS", "simulate", "build", "truth_settings", "decay_rate", "STIFF_DECAY_RATE"]

# A scene whose linearised equations at the initial state decay faster than this (1/s) is stiff for the
# truth: DOP853's explicit steps are then held to its stability bound (~3.3 / rate), not to its accuracy.
# Measured on flyball_governor (8117 1/s): DOP853 at 1e-12 takes 3959 steps (47513 evaluations) per second
# of motion, Radau 10729 evaluations for the same accuracy (3e-13 apart). The undamped scenes decay at 0,
# and no case but the damped governor comes within two orders of this.
STIFF_DECAY_RATE = 1e3
# Central differences for the linearisation: the step relative to each coordinate's size (~eps^(1/3),
# the step that balances truncation and roundoff).
_JACOBIAN_STEP = 1e-6

# Option "formulation": how the equations of motion are written.
FORMULATIONS = {
    "newton-euler": lambda scene: NewtonEuler(scene, "quaternion"),
    "newton-euler-matrix": lambda scene: NewtonEuler(scene, "matrix"),
    "kane": lambda scene: ClosedLoops(scene) if scene.loops else Kane(scene),  # loops: Kane + multipliers
    "planar": PlanarChain,  # serial revolute chains with parallel axes under gravity (planar.why_not)
}


def default_formulation(scene):
    """Newton-Euler for scenes of free bodies only, Kane otherwise."""
    return "newton-euler" if all(j.kind == "free" for j in scene.joints) and not scene.loops else "kane"


def build(scene, settings, times):
    """Check ``settings`` against ``times`` and build the system, before anything runs.

    Returns ``(system, integrator_settings)``; raises ValueError naming the field.
    """
    if scene.contacts:  # never integrate a contact scene as if nothing touched
        raise ValueError(f"scene.contacts: {[c.name for c in scene.contacts]} — the reference solver has no contact "
                         "(it integrates smooth equations of motion); a contact case's truth is its closed form")
    options = dict(settings.options)
    formulation = options.pop("formulation", default_formulation(scene))
    if formulation not in FORMULATIONS:
        raise ValueError(f"options.formulation: unknown {formulation!r} — use one of {sorted(FORMULATIONS)}")
    inner = replace(settings, options=options)
    check_settings(inner, times)
    return FORMULATIONS[formulation](scene), inner


def simulate(scene, times, settings):
    """Integrate ``scene`` and sample it at ``times``.

    Parameters
    ----------
    scene : Scene
    times : ndarray (n,) — sample times (s), strictly increasing, from 0
    settings : Settings — integrator name, dt or tolerances, options
        (``formulation``: one of ``FORMULATIONS``)

    Returns
    -------
    trajectory : Trajectory (NaN after a divergence)
    stats : Stats — steps and right-hand-side evaluations
    wall_s : float — wall time of the integration alone (s)
    """
    times = np.asarray(times, dtype=float)
    system, inner = build(scene, settings, times)
    start = time.perf_counter()
    Q, V, stats = INTEGRATORS[inner.integrator]().run(system, times, inner)
    wall = time.perf_counter() - start
    return system.trajectory(times, Q, V), stats, wall


def decay_rate(scene):
    """The fastest decay of ``scene``'s motion near its initial state (1/s): the largest ``-Re(lambda)``
    over the eigenvalues ``lambda`` of the equations of motion linearised there (central differences
    of the default formulation's ``(q', v')`` in the embedded coordinates). Only dampers make it large
    (an undamped stiff spring oscillates: imaginary eigenvalues, which an explicit method must resolve
    anyway), so a scene without a damper is 0 without computing anything."""
    if not any(sp.damping > 0.0 for sp in scene.springs):
        return 0.0
    _, rhs, y0 = first_order(FORMULATIONS[default_formulation(scene)](scene))
    J = np.empty((len(y0), len(y0)))
    for i in range(len(y0)):
        h = _JACOBIAN_STEP * max(1.0, abs(y0[i]))
        e = np.zeros_like(y0)
        e[i] = h
        J[:, i] = (rhs(0.0, y0 + e) - rhs(0.0, y0 - e)) / (2.0 * h)
    return float(max(0.0, -np.linalg.eigvals(J).real.min()))


def truth_settings(scene=None):
    """The reference's own truth settings where no closed form exists: DOP853 at its truth tolerances,
    on the planar formulation for a planar chain (``planar.why_not``: the same equations as Kane's
    in absolute angles, O(n^2) per evaluation: 50x faster than Kane at 64 links), Radau at the same
    tolerances for a stiff scene (``decay_rate`` above ``STIFF_DECAY_RATE``), else DOP853 on the
    default formulation."""
    from dalembert.settings import Settings

    if scene is not None and why_not(scene) is None:
        return Settings("dop853", rtol=DOP853.TRUTH_RTOL, atol=DOP853.TRUTH_ATOL, options={"formulation": "planar"})
    if scene is not None and decay_rate(scene) > STIFF_DECAY_RATE:
        return Settings("radau", rtol=DOP853.TRUTH_RTOL, atol=DOP853.TRUTH_ATOL)
    return Settings("dop853", rtol=DOP853.TRUTH_RTOL, atol=DOP853.TRUTH_ATOL)
