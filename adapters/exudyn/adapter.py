"""``ExudynAdapter``: the contract (``dalembert.adapters``) for Exudyn, with its own solvers.

The system is built by ``model.build`` (``describe`` gives its summary, kept for
reports), solved and sampled by ``sampling.solve``, read back in body terms by
``readback`` and audited by ``audit``. Console output is switched off while solving.

Solvers by name: ``generalized-alpha`` (options ``spectral_radius``,
``newton_rtol``, ``newton_atol`` — Exudyn's default Newton tolerances cap its
accuracy), ``trapezoidal-index2``, ``explicit-euler``, ``explicit-midpoint``,
``rk33``, ``rk44``, ``rk67``, ``velocity-verlet`` (fixed step) and ``dopri5``,
``ode23`` (adaptive: ``rtol``/``atol``, driven sample by sample). ``DVERK6`` is
listed by Exudyn 1.13 but not implemented, so it is not offered. Loop closures
(``Scene.loops``, built by ``model``) run with the two implicit solvers only; each
loop's force ON its body b is read back as ``reaction_force:<loop name>``. Spring-dampers
(``Scene.springs``, ``springs``) run with every solver and both joint formulations; the audit reads
each back from the system that ran. Prismatic joints (``joint:prismatic``) are built in both joint
formulations (``model``); like revolute ones, on a free body only with redundant joints, and with
redundant joints only by the implicit solvers. Every joint is read back from the system that ran
(``joints.read_joints``: its type, axis, joint point, initial coordinate) into the audit's
``joint_readout``. A solver that
stops before the end raises, and the run is stored as ``failed`` with the time
reached.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from packaging.specifiers import SpecifierSet

from dalembert.adapters.base import Adapter, IntegratorSpec, Option, Outcome, Prepared
from dalembert.adapters.exudyn import compat, contact, sampling
from dalembert.adapters.exudyn.loops import loop_axes
from dalembert.adapters.exudyn.model import MODEL_OPTIONS, ExudynSystem, NODES, TREE_JOINTS, build, rigid_bodies
from dalembert.adapters.exudyn.audit import audit
from dalembert.adapters.exudyn.readback import STALE_ACCELERATIONS, link_accelerations, read_back
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS, WORLD

__all__ = ["ExudynAdapter", "ExudynPrepared", "SamplingState"]

IMPLICIT = {"generalized-alpha": "GeneralizedAlpha", "trapezoidal-index2": "TrapezoidalIndex2"}
EXPLICIT = {"explicit-euler": "ExplicitEuler", "explicit-midpoint": "ExplicitMidpoint", "rk33": "RK33",
            "rk44": "RK44", "rk67": "RK67", "velocity-verlet": "VelocityVerlet", "dopri5": "DOPRI5", "ode23": "ODE23"}
ADAPTIVE = ("dopri5", "ode23")
# The order each scheme is built to (Exudyn's documentation of its solvers; Hairer, Norsett & Wanner I for the
# explicit tableaux, Arnold & Bruls 2007 for generalized-alpha on index-3 multibody systems): declared, and
# measured by the observed order.
ORDER = {"generalized-alpha": 2, "trapezoidal-index2": 2, "explicit-euler": 1, "explicit-midpoint": 2, "rk33": 3,
         "rk44": 4, "rk67": 6, "velocity-verlet": 2, "dopri5": 5, "ode23": 3}
STAGES = {"rk44": 4, "rk33": 3, "rk67": 7, "explicit-midpoint": 2, "dopri5": 7, "ode23": 4}
OPTIONS = ("node", "joints", "spectral_radius", "newton_rtol", "newton_atol", *contact.OPTIONS)
# Newton tolerances used unless the options say otherwise: Exudyn's defaults
# (1e-8 relative, 1e-10 absolute) cap generalized-alpha's accuracy (measured: an orientation
# error of 9.4e-3 rad instead of 2.6e-6 on the intermediate-axis top at dt = 1e-4).
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14
# ... but a scene with contact runs at Exudyn's own defaults unless the options say otherwise: Newton fails at the
# tighter ones (measured: ball_slide_to_roll at dt = 1e-3 and 1e-4, within 0.15 s) against penalty forces of
# ~1e6 N/m times the penetration.
CONTACT_NEWTON_RTOL = 1e-8
CONTACT_NEWTON_ATOL = 1e-10
# The Exudyn versions whose TrapezoidalIndex2 runs a ball joint in redundant coordinates. Measured on 1.11.0
# (heavy_top, joints=redundant, either node): Newton stalls at t = 0 (relative error 0.89 at every step Exudyn
# tries, down to its minimum) on a solve that is not its process's first — a repeat of one system or a fresh one
# alike, whatever the current configuration is reset to — so a run's timed repeats fail; 1.13.6 runs it.
BALL_TRAPEZOIDAL = ">=1.13"


def newton_tolerances(scene, settings):
    """generalized-alpha's Newton tolerances ``(relative, absolute)`` for ``scene`` at ``settings``: the options',
    else ``NEWTON_RTOL``/``NEWTON_ATOL``, or Exudyn's own defaults for a scene with contact."""
    rtol, atol = (CONTACT_NEWTON_RTOL, CONTACT_NEWTON_ATOL) if scene.contacts else (NEWTON_RTOL, NEWTON_ATOL)
    o = settings.options
    return float(o.get("newton_rtol", rtol)), float(o.get("newton_atol", atol))


@dataclass
class SamplingState:
    """How a prepared system's solves are sampled: the one thing its runs learn and keep.

    Attributes
    ----------
    late : str or None — why Exudyn's stored sensors missed a sample of one of its solves (every later solve
        then samples from Python, ``sampling.solve(stored=False)``); None while they have missed none
    """

    late: str | None = None


@dataclass(frozen=True, eq=False)
class ExudynPrepared(Prepared):
    """Exudyn's prepared run (``Prepared``): the system, built and assembled once (Exudyn's solvers start every
    solve from its initial configuration, so each solve of it repeats the first bit for bit: measured on every
    run of the default matrix Exudyn supports, three solves of one system against one of a fresh system each).

    Attributes
    ----------
    system : ExudynSystem — the system (``model.build``), what the read-back and the audit read
    sampling : SamplingState — whether its solves sample through Exudyn's stored sensors or from Python
    """

    system: ExudynSystem
    sampling: SamplingState


class ExudynAdapter(Adapter):
    """Exudyn (``exudyn``), its own solvers."""

    name = "exudyn"
    # ball joints and welds only with joints=redundant, loops only with implicit solvers (see ``unsupported``)
    # contact: sphere-sphere and sphere-plane connectors, implicit solvers only (``contact``, ``contact.why_not``)
    effects = EFFECTS | LOOP_EFFECTS | SPRING_EFFECTS | CONTACT_EFFECTS
    # Measured in engine environments: 1.13.6 (dalembert's), and 1.11.0 (the release before 1.13 with a CPython 3.11
    # wheel; no 1.12 has one) through ``compat``'s shim, with one refusal (``BALL_TRAPEZOIDAL``). 1.9.0 fails every run
    # on its import of ObjectContactSphereSphere, which it lacks (the contact connectors would be a port); 1.10.0 is
    # not measured.
    supported_versions = ">=1.11"
    unsupported_versions_why = ("measured on 1.11.0 and 1.13.6 only (adapters/exudyn/compat.py: what differs); 1.9.0 "
                                "has no ObjectContactSphereSphere, which the adapter imports")
    options = {
        **MODEL_OPTIONS,  # node, joints
        "spectral_radius": Option(minimum=0.0, maximum=1.0, only=("generalized-alpha",),
                                  description="generalized-alpha's spectral radius at infinity (default: Exudyn's)"),
        "newton_rtol": Option(default=NEWTON_RTOL, exclusive_minimum=0.0, only=("generalized-alpha",),
                              description=f"Newton's relative tolerance (with contact: {CONTACT_NEWTON_RTOL:g})"),
        "newton_atol": Option(default=NEWTON_ATOL, exclusive_minimum=0.0, only=("generalized-alpha",),
                              description=f"Newton's absolute tolerance (with contact: {CONTACT_NEWTON_ATOL:g})"),
        **contact.CONTACT_OPTIONS,  # contact_stiffness, friction_zone
    }
    integrators = {
        **{k: IntegratorSpec(True, OPTIONS, f"Exudyn {v}", order=ORDER[k]) for k, v in IMPLICIT.items()},
        **{k: IntegratorSpec(k not in ADAPTIVE, OPTIONS, f"Exudyn {v}", order=ORDER[k])
            for k, v in EXPLICIT.items()},
    }

    def version(self):
        import exudyn

        return exudyn.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        if settings.integrator in ADAPTIVE and settings.rtol is None:
            raise ValueError(f"rtol: {settings.integrator!r} is adaptive — give rtol (and atol)")

    def unsupported(self, scene, settings):
        reason = super().unsupported(scene, settings)
        if reason:
            return reason
        node = self.option(settings, "node")
        redundant = self.option(settings, "joints") == "redundant"
        explicit = settings.integrator in EXPLICIT
        if (why := contact.why_not(scene, settings, rigid_bodies(scene, redundant), explicit)):
            return why
        if scene.loops and explicit:
            return ("loop closures with an explicit integrator: Exudyn's explicit solvers solve no algebraic "
                    "constraints (a closure is an index-3 DAE: use generalized-alpha or trapezoidal-index2)")
        for name, rows in loop_axes(scene).items() if scene.loops else ():
            if rows.axes == (0,):
                return (f"loop {name!r}: a distance loop whose one row is redundant at the initial state — Exudyn's "
                        "Newton solver needs independent constraint rows (exudyn.loops)")
        if (redundant and settings.integrator == "trapezoidal-index2" and any(j.kind == "ball" for j in scene.joints)
                and not SpecifierSet(BALL_TRAPEZOIDAL).contains(self.version(), prereleases=True)):
            return (f"exudyn {self.version()}: trapezoidal-index2 on a ball joint in redundant coordinates stalls "
                    f"Newton at t = 0 on every solve but its process's first (exudyn{BALL_TRAPEZOIDAL} runs it) — "
                    "use generalized-alpha")
        if node == "ep" and explicit and rigid_bodies(scene, redundant):
            return ("Exudyn: explicit integrator detected node which contains algebraic variables — "
                    "Euler-parameter nodes need an implicit solver")
        if redundant:
            if explicit and any(j.kind != "free" for j in scene.joints):
                return ("Exudyn: explicit integrator detected object which contains constraints that cannot be "
                        "solved — redundant-coordinate joints (an index-3 DAE) need an implicit solver")
            return None
        kinds = sorted({j.kind for j in scene.joints if j.kind in ("ball", "weld")})
        if kinds:
            return (f"joint:{', joint:'.join(kinds)} with joints=minimal: ObjectKinematicTree has single-axis "
                    f"joints only — use --option joints=redundant")
        free = {j.child for j in scene.joints if j.kind == "free"}
        for j in scene.joints:
            if j.kind in TREE_JOINTS and j.parent != WORLD and j.parent in free:
                return (f"a {j.kind} joint on a free body: the kinematic tree here has a fixed base — use "
                        "--option joints=redundant")
        return None

    def variants(self, scene):
        """Default matrix: each node type where the scene has rigid-body nodes, both joint formulations
        where it has joints, the redundant one on rotation-vector (the default) and Euler-parameter nodes
        (whose joint reactions are exact where the rotation-vector node's are not: audit.ROTVEC_LG_REACTION)."""
        out = [{}]
        if any(j.kind == "free" for j in scene.joints):
            out += [{"node": n} for n in NODES if n != "rotvec-lg"]
        if any(j.kind != "free" for j in scene.joints):
            out += [{"joints": "redundant"}, {"joints": "redundant", "node": "ep"}]
        return out

    # ------------------------------------------------------------- build
    def describe(self, scene, settings):
        return build(scene, settings, assemble=False).summary

    def prepare(self, scene, times, settings):
        # The system is built once (``ExudynPrepared``: its solves repeat bit for bit); ``run`` sets
        # ``sampling.late`` once Exudyn's stored sensors have missed a sample of it (then it samples from Python)
        return ExudynPrepared(scene, np.asarray(times, dtype=float), settings, build(scene, settings), SamplingState())

    # ------------------------------------------------------------- run
    def _settings(self, p):
        import exudyn as exu

        s = exu.SimulationSettings()
        st = p.settings
        times = p.times
        compat.no_solution_file(s)
        s.timeIntegration.verboseMode = 0
        s.timeIntegration.endTime = float(times[-1])
        s.timeIntegration.startTime = float(times[0])
        compat.set_solver(s, getattr(exu.DynamicSolverType, {**IMPLICIT, **EXPLICIT}[st.integrator]))
        if st.integrator in ADAPTIVE:
            s.timeIntegration.automaticStepSize = True
            s.timeIntegration.relativeTolerance = float(st.rtol)
            s.timeIntegration.absoluteTolerance = float(st.atol if st.atol is not None else st.rtol)
            s.timeIntegration.numberOfSteps = 1  # Exudyn's largest step = horizon / numberOfSteps: the samples cap it
            s.timeIntegration.initialStepSize = float(times[1] - times[0])
            s.timeIntegration.minimumStepSize = sampling.MIN_STEP_FRACTION * float(times[1] - times[0])
        else:
            s.timeIntegration.automaticStepSize = False
            s.timeIntegration.numberOfSteps = int(round((times[-1] - times[0]) / st.dt))
        if st.integrator == "generalized-alpha":
            radius = self.option(st, "spectral_radius")
            if radius is not None:  # else Exudyn's own default
                s.timeIntegration.generalizedAlpha.spectralRadius = float(radius)
            rtol, atol = newton_tolerances(p.scene, st)
            s.timeIntegration.newton.relativeTolerance = rtol
            s.timeIntegration.newton.absoluteTolerance = atol
        if p.scene.contacts:
            # the run steps at the user's dt (its samples must land on its steps): Exudyn's contact connectors
            # otherwise shrink the step at each impact to the one they recommend, off the grid for good
            s.timeIntegration.discontinuous.useRecommendedStepSize = False
        return s

    def run(self, prepared):
        import exudyn as exu

        p = prepared
        times, integrator = p.times, p.settings.integrator
        console = exu.config.printToConsole
        exu.config.printToConsole = False  # silent unless the user asks (Exudyn prints solver banners)
        try:
            # once Exudyn's own sampling has missed a sample of this run, its next solves sample from Python
            # at once: the run repeats the same steps, and a solve thrown away was the timed repeats' overhead
            late = p.sampling.late
            solved = self._solve(p, stored=late is None)
            if late is None and solved.late is not None:  # Exudyn's own sampling missed a sample
                late = p.sampling.late = solved.late
                solved = self._solve(p, stored=False)
            if late is not None:
                solved = replace(solved, sampling=f"from Python ({late})")
        finally:
            exu.config.printToConsole = console
        built, it, error, read = p.system, solved.it, solved.error, solved.read
        # complete = every sample read (Exudyn's accumulated time may end a few ulps short of the horizon)
        if error is not None or read != len(times):
            missing = "" if read == len(times) else f" ({len(times) - read} sample(s) not reached)"
            if solved.stalled is not None:  # our stop, not Exudyn's: its message would only echo ours
                missing, error = f"{missing}: {solved.stalled}", None
            raise RuntimeError(f"Exudyn solver stopped at t = {solved.reached:g} s of {times[-1]:g} s{missing}"
                               + (f": {error}" if error else ""))

        def read():
            if built.links and integrator in EXPLICIT:
                # explicit solvers keep no accelerations at sample 0, and some none of the sampled state
                # at any sample (STALE_ACCELERATIONS): Exudyn evaluates them at the sampled states instead
                link_accelerations(p, solved.values, range(len(times)) if integrator in STALE_ACCELERATIONS else [0],
                                   lambda: self._settings(p))
            return read_back(p, built, solved.values)

        rejected = int(it.rejectedAutomaticStepSizeSteps) if it is not None else 0
        info = {"newton_steps": int(it.newtonStepsCount) if it is not None else 0, "rejected_steps": rejected,
                "sampling": solved.sampling}
        n_rhs = (solved.steps + rejected) * STAGES.get(integrator, 1)
        return Outcome(read, solved.wall, solved.steps, n_rhs, info)

    def _solve(self, p, stored):
        """One solve of the prepared system: ``sampling.solve`` on it (a ``Solved``)."""
        st, system = p.settings, p.system
        return sampling.solve(system.mbs, system.sensors, self._settings(p), p.times,
                              None if st.integrator in ADAPTIVE else st.dt, stored)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        out = audit(prepared, outcome, {**IMPLICIT, **EXPLICIT}[prepared.settings.integrator])
        if prepared.scene.contacts:  # the solver settings contact changes (``_settings``)
            out["recommended_step_size"] = "off: the steps stay on the run's dt (Exudyn's connectors would shrink them)"
            if prepared.settings.integrator == "generalized-alpha":
                out["newton_tolerances"] = list(newton_tolerances(prepared.scene, prepared.settings))
        return out
