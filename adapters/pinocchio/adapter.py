"""``PinocchioAdapter``: the contract (``dalembert.adapters``) for Pinocchio.

The scene through Pinocchio's dynamics (ABA, RNEA; ``model``: free, revolute,
prismatic, ball and weld joints), with the
integrators owned here (``integrators``), so their quality is part of what is
measured. The fixed-step loops run compiled (``native``: the same integrators
and loads in ``stepper.cpp`` against the installed Pinocchio, no Python call per
step), or in Python with ``--option loop=python`` and wherever the compiled loop
cannot be built (the audit says which ran). Welds as constraints and loop
closures (``loops``: ball and revolute; distance is unsupported) run
``pin.constraintDynamics``, which the compiled loop does not have: their
fixed-step runs take the Python loop. Spring-dampers (``springs``) are external
forces at every evaluation, in every loop; the audit identifies each one's
stiffness, damping and rest length from the dynamics the run used. Contact
(``contact``: Pinocchio solves a contact problem at one instant but steps none)
is the adapter's own time-stepper on ``euler``: the scene's pairs detected each
step, one cone complementarity problem solved by ``pin.ADMMConstraintSolver``
or ``pin.PGSConstraintSolver`` (option ``contact_solver``), impulses at the
velocity level, in Python; other integrators, constraints and box-box pairs
refuse contact scenes (``contact.why_not``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dalembert.adapters import file_model
from dalembert.adapters.base import Adapter, IntegratorSpec, Option, Outcome, Prepared, typed_options
from dalembert.adapters.pinocchio import contact, from_file, loops
from dalembert.adapters.pinocchio.audit import audit
from dalembert.adapters.pinocchio.integrators import STAGES, adaptive, fixed_step
from dalembert.adapters.pinocchio.model import WELDS, PinocchioModel
from dalembert.adapters.pinocchio.readback import REACTING, read_back
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, SPRING_EFFECTS
from dalembert.settings import steps_per_interval

__all__ = ["PinocchioAdapter", "PinocchioPrepared"]

# Fixed-step loops: compiled (stepper.cpp, the default) or the Python one
# (the same integrators, kept as the readable specification and the fallback).
LOOPS = ("native", "python")


@dataclass(frozen=True, eq=False)
class PinocchioPrepared(Prepared):
    """Pinocchio's prepared run (``Prepared``): the model, its initial state and, for the fixed-step integrators,
    the compiled loop.

    Attributes
    ----------
    pm : PinocchioModel — the scene as a ``pin.Model`` with its loads, springs and constraints (``model``)
    q0 : ndarray (nq,) — the initial configuration, Pinocchio's coordinates (quaternions ``(x, y, z, w)``)
    v0 : ndarray (nv,) — the initial velocity, each joint's in its LOCAL frame
    steps : ndarray (n - 1,) of int, or None — steps per sample interval (fixed-step integrators; None: adaptive)
    native : native.NativeModel or None — the compiled loop (``stepper.cpp``), where it runs
    native_error : str — why the compiled loop could not be loaded or built ("" where it was, or was not asked for)
    contacts : contact.Contacts or None — the scene's contact pairs as the contact time-stepper detects them (None:
        no contact pairs)
    """

    pm: object
    q0: np.ndarray
    v0: np.ndarray
    steps: np.ndarray | None
    native: object = None
    native_error: str = ""
    contacts: object = None


class PinocchioAdapter(Adapter):
    """Pinocchio (``pin``), integrators owned by the adapter."""

    name = "pinocchio"
    # loop:distance: loops.DISTANCE_REASON; contact: euler only, the rest as contact.why_not says
    effects = EFFECTS | SPRING_EFFECTS | frozenset(f"loop:{k}" for k in loops.LOOP_KINDS) | CONTACT_EFFECTS
    options = {
        "loop": Option(LOOPS, LOOPS[0], "the fixed-step loop: compiled (stepper.cpp) or the Python one"),
        "welds": Option(WELDS, WELDS[0], "welds as one rigid body (tree) or as constraints (pin.constraintDynamics)"),
        **contact.CONTACT_OPTIONS,  # contact_solver, contact_tolerance, contact_iterations (euler)
        **file_model.FILE_OPTIONS,  # model_file, file_effects: the URDF read by Pinocchio itself (from_file)
    }
    _file = file_model.FILE_OPTION_NAMES
    integrators = {
        "euler": IntegratorSpec(True, ("loop", "welds", *contact.OPTIONS, *_file),
                                "semi-implicit Euler on the group; with contact, the contact time-stepper (impulses "
                                "from pin's ADMM or PGS cone solver each step)", order=1),
        "rk4": IntegratorSpec(True, ("loop", "welds", *_file),
                              "Runge-Kutta-Munthe-Kaas 4 (exact dexp^-1 from dIntegrate)",
                              order=4),
        # The order the name claims: on a joint whose group does not commute (free, ball) the missing dexp^-1
        # correction makes it second order (Munthe-Kaas, BIT 38, 1998), which the observed order shows.
        "rk4-naive": IntegratorSpec(True, ("loop", "welds", *_file),
                                    "RK4 with stagewise integrate, no dexp^-1 correction",
                                    order=4),
        "rk45": IntegratorSpec(False, ("welds", *_file), "scipy RK45 in local coordinates", order=5),
        "dop853": IntegratorSpec(False, ("welds", *_file), "scipy DOP853 in local coordinates", order=8),
    }

    def version(self):
        import pinocchio

        return pinocchio.__version__

    def beyond_scene(self, scene, settings):
        return file_model.beyond(settings)  # the robot file's effects, when the engine reads the file with them

    def unsupported(self, scene, settings):
        if (why := file_model.why_not(scene, settings)):
            return why
        constrained = bool(scene.loops) or (self.option(settings, "welds") == "constraint"
                                            and any(j.kind == "weld" for j in scene.joints))
        if (why := contact.why_not(scene, settings, constrained)):  # contact: euler, welds as a tree, no box-box
            return why
        if any(lp.kind == "distance" for lp in scene.loops):
            return loops.DISTANCE_REASON
        reason = super().unsupported(scene, settings)
        if reason or self.option(settings, "welds") != "constraint":
            return reason
        if scene.loads:
            return ("welds=constraint with loads: pin.constraintDynamics takes no external forces — "
                    "use welds=tree")
        if scene.springs:
            return ("welds=constraint with spring-dampers: pin.constraintDynamics takes no external forces (and the "
                    "springs' joint torques are not checked against welds held by constraints) — use welds=tree")
        if any(j.kind in REACTING for j in scene.joints):
            return ("welds=constraint with revolute, prismatic or ball joints: their reactions would miss the "
                    "constraint forces — use welds=tree")
        return None

    def repro(self, scene, times, settings, quantity):
        if file_model.model_file(settings):
            raise ValueError(file_model.NO_REPRO)
        return super().repro(scene, times, settings, quantity)

    def variants(self, scene):
        """Default matrix: where the scene has welds, also as constraints (where supported)."""
        out = [{}]
        if any(j.kind == "weld" for j in scene.joints):
            out.append({"welds": "constraint"})
        return out

    def describe(self, scene, settings):
        if file_model.model_file(settings):
            return from_file.describe(scene, settings)
        pm = PinocchioModel(scene, self.option(settings, "welds"))
        return pm.summary + "\n" + "".join(f"{line}\n" for line in contact.Contacts(pm, scene).summary())

    def prepare(self, scene, times, settings):
        from dalembert.adapters.pinocchio import native

        if file_model.model_file(settings):
            return from_file.prepare(scene, times, settings)
        pm = PinocchioModel(scene, self.option(settings, "welds"))
        q0, v0 = pm.initial_state()
        times = np.asarray(times, dtype=float)
        steps = steps_per_interval(times, settings.dt) if settings.dt else None
        compiled, error = None, ""
        contacts = contact.Contacts(pm, scene) if scene.contacts else None
        # the compiled loop is loaded (or built) here, with the model, never inside a timed run
        if steps is not None and self.option(settings, "loop") == "native" and not pm.constrained and not contacts:
            try:
                compiled = native.NativeModel(pm)
            except RuntimeError as e:  # not built here: the Python loop runs, saying why
                error = str(e)
        return PinocchioPrepared(scene, times, settings, pm, q0, v0, steps, compiled, error, contacts)

    # ------------------------------------------------------------ stepping
    def run(self, prepared):
        if isinstance(prepared, file_model.FilePrepared):
            return from_file.run(prepared)
        p = prepared
        method = p.settings.integrator
        info = {}
        start = time.perf_counter()
        if method in ("rk45", "dop853"):
            s = p.settings
            Q, V, n_steps, n_rhs = adaptive(p.pm, method.upper(), p.q0, p.v0, p.times, s.rtol, s.atol)
            info["loop"] = "Python around scipy solve_ivp"
        elif p.contacts is not None:  # the contact time-stepper (contact.why_not: euler only)
            options = typed_options(contact.CONTACT_OPTIONS, p.settings)
            Q, V, n_steps, n_rhs, info["contact"] = contact.fixed_step(p.pm, p.contacts, options, p.q0, p.v0,
                                                                       p.times, p.steps)
            info["loop"] = "Python (the contact time-stepper, adapters/pinocchio/contact.py: the compiled loop has none)"
        else:
            Q, V, n_steps, n_rhs, info["loop"] = self._fixed_loop(p, method)
        wall = time.perf_counter() - start
        return Outcome(lambda: read_back(p, Q, V), wall, n_steps, n_rhs, info)

    def _fixed_loop(self, p, method):
        """The compiled loop (``native``) unless ``options.loop`` is ``python`` or it cannot be
        built; the fifth item says which ran, and why not the compiled one."""
        pm = p.pm
        args = (pm, method, p.q0, p.v0, p.times, p.steps)
        if self.option(p.settings, "loop") == "python":
            return (*fixed_step(*args), "Python (options.loop = python)")
        if pm.constrained:
            return (*fixed_step(*args), "Python (constraint dynamics: the compiled loop has aba only)")
        if p.native is None:
            return (*fixed_step(*args), f"Python (the compiled loop is unavailable: {p.native_error})")
        Q, V, n, error = p.native.run(method, p.q0, p.v0, p.times, p.steps)
        loop = "C++ (adapters/pinocchio/stepper.cpp)" + (f"; stopped: {error}" if error else "")
        return Q, V, n, n * STAGES[method], loop

    # ------------------------------------------------------------ read-back, audit
    def audit(self, prepared, outcome):
        if isinstance(prepared, file_model.FilePrepared):
            return from_file.audit(prepared, outcome)
        return audit(prepared, outcome)
