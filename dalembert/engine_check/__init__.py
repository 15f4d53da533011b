"""``dalembert check-engine``: a battery of probes with known answers that finds what goes wrong in real adapters.

Each probe builds a small scene in code (``engine_check.scenes``), runs it through the adapter exactly as the
harness would (``check``, ``unsupported``, ``prepare``, ``run``, the read-back, ``audit``) and compares what comes
back with an answer known in closed form. Every probe runs, whatever the others found; the result lists every
problem (``Problem``: the probe, what it saw, what to look at), never the first only. A probe whose scene the
engine declares unsupported is not a problem: it is a note, and the refusal probe checks that the refusal is real.

The probes, one family per module (each registers with ``@probe``):

* ``probes_motion``: effects the scene did not call for — energy lost on a free spin (damping), gravity not the
  scene's, a hinge that does not swing as gravity drives it (a motor, a limit), contact where none was asked —,
  and mass and inertia as the engine uses them, from motion (a = F/m, w' = I^-1 torque, Euler's equations);
* ``probes_frames``: frames and conventions — angular velocity in world axes, quaternion order w, x, y, z, a
  revolute axis in its parent's frame, the reaction's sign and the body it acts on;
* ``probes_contract``: the same run twice bit for bit (state reset), the observed order of each fixed-step
  integrator against its ``IntegratorSpec.order``, unsupported effects really refused, nothing printed (on
  import, load or run: file descriptors 1 and 2, where engines print from C), and a minimum of supported cases.

Usage: ``dalembert check-engine NAME`` (``harness.commands.check_engine``) or, in an engine's own tests,
``dalembert.testing.check_engine(name)``. The guide: ``docs/engines.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Problem", "EngineCheck", "NotApplicable", "Probing", "PROBES", "probe", "check_engine", "PROBE_DT",
           "PROBE_RTOL", "ROUNDOFF_REL_TOL"]

# The fixed step the probes run with (s): short horizons (<= 0.5 s) at this step are a few hundred steps, and
# the probes' tolerances hold for a first-order integrator at it (each probe's constants say why).
PROBE_DT = 1e-3
# The adaptive integrators' tolerance in the probes: tight enough that every tolerance sized for a first-order
# fixed step at PROBE_DT holds with a wide margin.
PROBE_RTOL = 1e-10
# Where the answer is exact for any consistent integrator (a constant acceleration, a steady spin, a body at rest)
# the error is roundoff: this allows ~100 float32 roundoffs (MJX's default precision, eps 1.2e-7; measured: MJX's
# free fall 1.1e-6, its steady spin 2.4e-6) and 1e11 double ones; the mistakes the probes look for are 1e-2 or more.
ROUNDOFF_REL_TOL = 1e-5


@dataclass(frozen=True)
class Problem:
    """One thing a probe found wrong.

    Attributes
    ----------
    probe : str — the probe's name (``[integrator]`` appended where it ran one)
    saw : str — what it saw, with the numbers and what they should have been
    look_at : str — where the mistake usually is, and the fix
    """

    probe: str
    saw: str
    look_at: str

    def __str__(self):
        return f"{self.probe}: {self.saw} — look at: {self.look_at}"


@dataclass(frozen=True)
class EngineCheck:
    """What ``check_engine`` found: every problem, and notes (probes that did not apply, figures measured).

    Attributes
    ----------
    engine : str
    integrators : tuple of str — the integrators the probes ran
    problems : tuple of Problem
    notes : tuple of str
    probes : tuple of str — every probe that ran
    """

    engine: str
    integrators: tuple
    problems: tuple
    notes: tuple
    probes: tuple

    @property
    def ok(self):
        return not self.problems


class NotApplicable(Exception):
    """Raised by a probe whose scene the engine does not run (declared unsupported, or refused by ``check``):
    a note, not a problem."""


@dataclass(frozen=True)
class _Entry:
    name: str
    function: object
    per_integrator: bool
    what: str


# name -> _Entry, in registration order (the order the probes run and report in)
PROBES = {}


def probe(name, per_integrator=True):
    """Register a probe: ``function(ctx) -> list of Problem`` (``ctx``: a ``Probing``). ``per_integrator``: run it
    once per integrator under check (``ctx.integrator``); else once per engine (``ctx.integrator`` is the first)."""
    def register(function):
        if name in PROBES:
            raise ValueError(f"probe: {name!r} is registered twice — give each probe its own name")
        PROBES[name] = _Entry(name, function, per_integrator, (function.__doc__ or "").strip().split("\n")[0])
        return function
    return register


@dataclass
class Probing:
    """What a probe is given: the engine under check and the integrator it runs, and a ``simulate`` that runs a
    scene through the adapter as the harness would.

    Attributes
    ----------
    name : str — the engine's registered name
    adapter : dalembert.adapters.Adapter
    integrator : str — the integrator this probe runs
    integrators : tuple of str — every integrator under check
    options : dict — engine options every run takes (where its integrator takes them)
    notes : list of str — a probe appends what it measured or could not measure
    """

    name: str
    adapter: object
    integrator: str
    integrators: tuple
    options: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def settings(self, dt=PROBE_DT, integrator=None):
        """``Settings`` for ``integrator`` (default: this probe's): ``dt`` if fixed-step, else ``PROBE_RTOL``."""
        from dalembert.settings import Settings

        integrator = integrator or self.integrator
        spec = self.adapter.integrators[integrator]
        options = {k: v for k, v in self.options.items() if k in spec.options}
        if spec.fixed_step:
            return Settings(integrator, dt=dt, options=options)
        return Settings(integrator, rtol=PROBE_RTOL, atol=PROBE_RTOL, options=options)

    def simulate(self, scene, times, settings=None, runs=1):
        """Run ``scene`` sampled at ``times`` (array (n,), s) as the harness would; returns ``(prepared, outcomes)``
        (``runs`` outcomes of ``run`` on one prepared model). ``NotApplicable`` when the engine refuses it."""
        settings = settings or self.settings()
        times = np.asarray(times, dtype=float)
        try:
            self.adapter.check(scene, times, settings)
        except ValueError as e:
            raise NotApplicable(f"{scene.name}: check() refused {settings.label()}: {e}") from None
        why = self.adapter.unsupported(scene, settings)
        if why:
            raise NotApplicable(f"{scene.name}: unsupported: {why}")
        prepared = self.adapter.prepare(scene, times, settings)
        return prepared, [self.adapter.run(prepared) for _ in range(runs)]

    def trajectory(self, scene, times, settings=None):
        """The ``Trajectory`` of one run of ``scene`` (``simulate``)."""
        return self.simulate(scene, times, settings)[1][0].trajectory


def check_engine(name, integrators=None, options=None):
    """Run every probe on the engine registered as ``name``; returns an ``EngineCheck`` listing every problem.

    Parameters
    ----------
    name : str — a registered engine (``dalembert engines``)
    integrators : iterable of str, optional — the integrators to probe (default: every one the engine has; the
        motion probes run the first, the order probe each fixed-step one, unless integrators are given: then the
        motion probes run each)
    options : dict, optional — engine options (text values, as ``--option``) for every run whose integrator takes
        them; one that none of the integrators takes is a ValueError

    Raises ImportError when the engine is not installed, ValueError naming an integrator it does not have.
    """
    from dalembert.adapters import get_adapter
    from dalembert.engine_check import capture
    from dalembert.registry import suggest

    adapter = get_adapter(name)
    given = tuple(integrators or ())
    for integ in given:
        if integ not in adapter.integrators:
            raise ValueError(f"--integrator: {name} has no {integ!r}{suggest(integ, adapter.integrators)}")
    every = given or tuple(adapter.integrators)
    options = dict(options or {})
    for key, value in options.items():
        takers = [i for i in every if key in adapter.integrators[i].options]
        if not takers:
            raise ValueError(f"--option: no integrator of {name} under check takes {key!r} — options: "
                             f"{', '.join(sorted(adapter.options)) or 'none'}")
        problem = adapter.options[key].problem(key, value, takers[0]) if key in adapter.options else None
        if problem:
            raise ValueError(f"--option {problem}")
    if not every:
        return EngineCheck(name, (), (Problem("integrators", f"{name} declares no integrators",
                                              "Adapter.integrators: name -> IntegratorSpec"),), (), ())
    with capture.output() as printed:
        adapter.version()
    problems, notes, ran = [], [], []
    if printed.text:
        problems.append(capture.printed_problem("version()", printed.text))
    for entry in PROBES.values():
        for integ in (given or every[:1]) if entry.per_integrator else every[:1]:
            label = f"{entry.name} [{integ}]" if entry.per_integrator else entry.name
            ctx = Probing(name, adapter, integ, every, options)
            with capture.output() as printed:
                try:
                    found = list(entry.function(ctx) or ())
                except NotApplicable as e:
                    found = []
                    ctx.notes.append(f"not run: {e}")
                except Exception as e:  # a probe's run raised: that is the finding (and the other probes go on)
                    found = [Problem(label, f"raised {type(e).__name__}: {e}",
                                     "the adapter's prepare/run/read-back on this probe's scene (a run that diverges "
                                     "returns NaN, never raises)")]
            problems += [Problem(label, p.saw, p.look_at) if p.probe == entry.name else p for p in found]
            if printed.text:
                problems.append(capture.printed_problem(label, printed.text))
            notes += [f"{label}: {n}" for n in ctx.notes]
            ran.append(label)
    return EngineCheck(name, every, tuple(problems), tuple(notes), tuple(ran))


# the probe families register themselves on import (motion first: the order they report in)
from dalembert.engine_check import probes_motion, probes_frames, probes_contract  # noqa: E402,F401
