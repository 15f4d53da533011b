"""The contract every case meets, for case authors: ``check_case(factory)``.

dalembert's own contract tests (``tests/test_case_contract.py``) run these same checks on every
registered case; a third party runs them on theirs::

    from dalembert.testing import check_case
    from my_package.my_cases import my_top

    def test_my_top():
        check_case(my_top)

Each ``check_*`` function raises ``CaseCheckError`` (an ``AssertionError``, so pytest reports it
as a failed test) naming the case and what is wrong; ``check_case`` runs them all and reports
every failure at once. They build the case and run the reference solver, nothing else: no
engine is needed. Conventions and a walk-through: ``docs/cases.md``.

For engine authors, ``check_engine(name)`` runs ``dalembert check-engine``'s probes on a registered engine
(``dalembert.engine_check``) and raises ``EngineCheckError`` listing every problem (``docs/engines.md``)::

    from dalembert.testing import check_engine

    def test_my_engine():
        check_engine("my_engine")
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

from dalembert import invariants, spatial
from dalembert.case import CASES, CaseFactory, load_cases
from dalembert.errors import QUANTITIES, trajectory_errors
from dalembert.kinds import CONTACT_EFFECTS
from dalembert.settings import Settings
from dalembert.trajectory import read_csv, write_csv

__all__ = ["CaseCheckError", "EngineCheckError", "check_case", "check_engine", "factory_of", "second_solution", "INITIAL_STATE_TOL",
           "HARD_HORIZON", "SECOND_RTOL", "contract_horizon", "REFERENCE_RTOL", "SINGULAR_RTOL", "check_builds", "check_truth_starts_at_initial_state",
           "check_truth_conserves", "check_reference_agrees", "check_floor", "check_csv_round_trip",
           "reference_cannot_judge"]

# The truth at t = 0 is the scene's initial state, to roundoff (m, rad, m/s, rad/s).
INITIAL_STATE_TOL = 1e-14
# Cases tagged ``hard`` are checked over this horizon (s): their full horizons cost minutes in the
# pure-Python reference.
HARD_HORIZON = 2.0
# Tolerance of the second solution (``second_solution``): the truth's own (DOP853 at 1e-12).
SECOND_RTOL = 1e-12
# Tolerance of the reference's DOP853 against a closed form: the truth's own, ~1e4 above double's
# roundoff on a smooth right-hand side.
REFERENCE_RTOL = 1e-12
# The same check's tolerance where DOP853 at REFERENCE_RTOL stops at a singular position of a closed
# loop: there the minimum-norm multipliers carry roundoff amplified by the loop Jacobian's vanishing
# singular value (~eps / sin(phi) on n_four_bar), above 1e-12 of the state, so the error controller
# shrinks its steps without end. Measured on n_four_bar (defaults, scipy 1.17, numpy 2.4): at 1e-12 the
# steps collapse to 6e-12 s at its flat instant (0.71436 s); at 1e-10 DOP853 passes it in 100 steps,
# 3.9e-14 rad from the closed form, 2.5e4 times inside the case's 1e-6 bound.
SINGULAR_RTOL = 1e-10


class CaseCheckError(AssertionError):
    """A case that breaks the contract; the message names the case and the check."""


def _fail(case_name, what):
    raise CaseCheckError(f"case {case_name!r}: {what}")


def factory_of(factory):
    """The ``CaseFactory`` of ``factory``: a registered name, a ``CaseFactory``, or the function decorated
    with ``@case`` (looked up in the registry; an unregistered function is wrapped as it is)."""
    if isinstance(factory, CaseFactory):
        return factory
    load_cases()
    if isinstance(factory, str):
        return CASES[factory]
    for _, registered in CASES.items():
        if registered.func is factory:
            return registered
    return CaseFactory(factory.__name__, factory, (), {})


def check_builds(factory, **params):
    """The case builds from ``params`` (defaults for the rest), deterministically, carries its factory's tags,
    states tolerances with reasons, and ``t_final`` reaches it (a longer horizon is another version)."""
    factory = factory_of(factory)
    case = factory(**params)
    if case.version != factory(**case.params).version:
        _fail(case.name, "two builds from the same parameters have different versions — the case depends on "
                         "something besides its parameters (randomness, the clock, a file)")
    if not (case.tags and set(factory.tags) <= set(case.tags)):
        _fail(case.name, f"tags {case.tags} do not include the factory's {factory.tags}")
    if not case.tolerances:
        _fail(case.name, "states no tolerances — give each quantity it is judged on a Tolerance(value, reason)")
    longer = factory(**{**case.params, "t_final": 2 * case.t_final})
    if longer.t_final != 2 * case.t_final or longer.version == case.version:
        _fail(case.name, "t_final=... does not set the horizon — pass the factory's t_final to Case")
    return case


def check_truth_starts_at_initial_state(case, truth):
    """The truth is finite, sampled at the case's times, and starts at the scene's initial state."""
    if not truth.is_finite():
        _fail(case.name, f"the truth is not finite (from t = {truth.first_nonfinite_time()} s)")
    if not np.array_equal(truth.t, case.times):
        _fail(case.name, "the truth is not sampled at the case's sample times")
    start = spatial.initial_body_states(case.scene)
    for name, s in start.items():
        b = truth.bodies[name]
        for what, got, want in (("position", b.position[0], s["p"]), ("velocity", b.velocity[0], s["v"]),
                                ("angular velocity", b.angular_velocity[0], s["w"])):
            if not np.allclose(got, want, rtol=0.0, atol=INITIAL_STATE_TOL * max(1.0, np.abs(want).max())):
                _fail(case.name, f"the truth's {what} of {name!r} at t = 0 is {got}, the scene's initial state {want}")
        angle = spatial.rotation_angle(b.quaternion[0], spatial.matrix_to_quat(s["R"]))
        if angle > INITIAL_STATE_TOL:
            _fail(case.name, f"the truth's attitude of {name!r} at t = 0 is {angle:.3g} rad off the scene's "
                             "initial one")
    for j in case.scene.joints:
        if j.name in truth.joints and j.kind != "ball":  # (a ball's quaternion may come out as -q0)
            if not np.allclose(truth.joints[j.name].q[0], j.q0, rtol=0.0, atol=INITIAL_STATE_TOL):
                _fail(case.name, f"the truth's joint {j.name!r} starts at {truth.joints[j.name].q[0]}, q0 is {j.q0}")


def check_truth_conserves(case, truth):
    """The truth keeps every conserved quantity, built-in or declared, within its tolerance."""
    for name in case.conserved:
        d = invariants.drift(name, case.scene, truth)
        if not d <= case.tolerances[name].value:
            _fail(case.name, f"the truth changes {name!r} by {d:.3g}, above its tolerance "
                             f"{case.tolerances[name].value:g} — the truth or the bound is wrong")
    for inv in case.invariants:
        try:
            d = inv.drift(case.scene, truth)
        except Exception as e:  # a series that cannot be computed is the case's bug
            _fail(case.name, f"invariant {inv.name!r}: its series fails on the truth: {type(e).__name__}: {e}")
        if not d <= inv.tolerance.value:
            _fail(case.name, f"the truth changes invariant {inv.name!r} by {d:.3g}, above its tolerance "
                             f"{inv.tolerance.value:g} — the series, its scale or the bound is wrong")


def second_solution(case):
    """The reference by a second route than the truth's: ``(label, trajectory)``.

    LSODA (scipy's Adams/BDF multistep methods, another family than the truth's one-step DOP853, or
    its one-step Radau for a stiff scene) at ``SECOND_RTOL`` on Kane's equations, which for a planar
    chain are also another formulation
    than the truth's (``reference.truth_settings``). Never the truth's own integrator and
    formulation: that would compare the truth with itself.
    """
    from dalembert.reference import simulate

    settings = Settings("lsoda", rtol=SECOND_RTOL, atol=SECOND_RTOL, options={"formulation": "kane"})
    return settings.label(), simulate(case.scene, case.times, settings)[0]


def reference_cannot_judge(case):
    """Why the reference solver cannot be the independent solution of ``case``, or None.

    A contact scene (``kinds.CONTACT_EFFECTS``): the reference integrates smooth equations of motion and has no
    contact, so it cannot check a contact case's closed form; such a case's independent check is its own test
    (an event-driven integration of the same motion: tests/test_contact_cases.py for the built-in ones)."""
    contact = sorted(case.scene.effects & CONTACT_EFFECTS)
    if contact:
        return (f"the scene calls for {', '.join(contact)}, which the reference solver does not model: its closed "
                "form is checked against an independent event-driven integration in its own tests instead")
    return None


def check_reference_agrees(case, truth):
    """An independent solution agrees with the truth within the case's tolerances (errors and drifts).

    With a closed form: the reference solver (DOP853 at ``REFERENCE_RTOL``) against it, or at
    ``SINGULAR_RTOL`` where the first stops at a singular position of a closed loop (the stop and the
    retry are named in any failure). Without: the truth (the reference) against ``second_solution``,
    never against itself. A case the reference cannot judge (``reference_cannot_judge``: contact) fails here,
    naming why; ``check_case`` leaves the check out for it.
    """
    why = reference_cannot_judge(case)
    if why:
        _fail(case.name, f"no independent solution from the reference: {why}")
    if case.exact is not None:
        label, other = _reference_through_singular_positions(case)
    else:
        label, other = second_solution(case)
    errors = trajectory_errors(other, truth)
    drifts = invariants.summary(case.scene, other, case.conserved, case.invariants).drifts
    for name, tol in case.tolerances.items():
        value = errors[name][0] if name in QUANTITIES and name in errors else drifts.get(name)
        if value is not None and not value <= tol.value:
            _fail(case.name, f"{label} and the truth differ in {name!r} by {value:.3g}, above the tolerance "
                             f"{tol.value:g} — the truth cannot judge engines at that bound")


def _reference_through_singular_positions(case):
    """``(label, trajectory)``: the reference's DOP853 at ``REFERENCE_RTOL``, or at ``SINGULAR_RTOL``
    when the first stops early (its steps collapsing at a singular position of a closed loop)."""
    from dalembert.reference import simulate

    traj, stats, _ = simulate(case.scene, case.times, Settings("dop853", rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL))
    if not stats.message:
        return f"the reference (dop853 rtol={REFERENCE_RTOL:g})", traj
    retry = Settings("dop853", rtol=SINGULAR_RTOL, atol=SINGULAR_RTOL)
    return (f"the reference (dop853 rtol={SINGULAR_RTOL:g}; at rtol={REFERENCE_RTOL:g} it stopped: "
            f"{stats.message})"), simulate(case.scene, case.times, retry)[0]


def check_floor(case):
    """No tolerance asks for more accuracy than the case's floor (``Case.floor``)."""
    for quantity, floor in case.floor().items():
        if not floor > 0.0:
            _fail(case.name, f"floor {quantity!r} is {floor!r}, not positive")
        if quantity in case.tolerances and case.tolerances[quantity].value < floor:
            _fail(case.name, f"tolerance {quantity!r} = {case.tolerances[quantity].value:g} is below the floor "
                             f"{floor:.3g} that double precision allows")


def check_csv_round_trip(case, truth, directory=None):
    """The truth written as CSV (``dalembert truth``) reads back bit for bit."""
    with tempfile.TemporaryDirectory(dir=directory) as tmp:
        path = os.path.join(tmp, "truth.csv")
        write_csv(truth, path)
        back = read_csv(path)
    for name, b in truth.bodies.items():
        for field in ("position", "quaternion", "velocity", "angular_velocity"):
            if not np.array_equal(getattr(back.bodies[name], field), getattr(b, field)):
                _fail(case.name, f"the truth's {name}.{field} does not survive the CSV round trip")


def contract_horizon(factory):
    """The horizon (s) the case contract checks ``factory``'s case over, or None for its own: a case tagged ``hard``
    shortened to ``HARD_HORIZON``, never lengthened (a hard case whose own ``t_final`` is shorter keeps it)."""
    if "hard" in factory.tags and factory.params["t_final"] > HARD_HORIZON:
        return HARD_HORIZON
    return None


def check_case(factory, horizon=None, **params):
    """Run every check of the case contract on ``factory`` (a function decorated ``@case``, its registered
    name, or a ``CaseFactory``) built with ``params``; raise ``CaseCheckError`` listing every failure.

    ``horizon`` (s) shortens the case (``t_final``); cases tagged ``hard`` default to ``contract_horizon``.
    Returns the case checked.
    """
    from dalembert.reference import truth as reference_truth

    factory = factory_of(factory)
    if horizon is None and "t_final" not in params:
        horizon = contract_horizon(factory)
    if horizon is not None:
        params = {**params, "t_final": horizon}
    case = check_builds(factory, **params)
    truth = reference_truth(case)
    failures = []
    checks = [check_truth_starts_at_initial_state, check_truth_conserves, check_csv_round_trip]
    if reference_cannot_judge(case) is None:  # (a contact case: its own tests check its closed form)
        checks.insert(2, check_reference_agrees)
    for check in checks:
        try:
            check(case, truth)
        except CaseCheckError as e:
            failures.append(str(e))
    try:
        check_floor(case)
    except CaseCheckError as e:
        failures.append(str(e))
    if failures:
        raise CaseCheckError(f"case {case.name!r}: {len(failures)} check(s) failed\n"
                             + "\n".join(f"  - {f}" for f in failures))
    return case


class EngineCheckError(AssertionError):
    """An engine's adapter that a probe of ``dalembert check-engine`` found wrong; the message lists every problem."""


def check_engine(name, integrators=None, options=None):
    """Run ``dalembert check-engine``'s probes on the engine registered as ``name`` (``dalembert.engine_check``);
    raise ``EngineCheckError`` listing every problem (its probe, what it saw, what to look at).

    ``integrators``, ``options``: as ``dalembert.engine_check.check_engine``. Returns the ``EngineCheck`` (its notes:
    the figures measured, the probes that did not apply).
    """
    from dalembert.engine_check import check_engine as probe_engine

    found = probe_engine(name, integrators, options)
    if found.problems:
        raise EngineCheckError(f"engine {name!r}: {len(found.problems)} problem(s)\n"
                               + "\n".join(f"  - {p}" for p in found.problems))
    return found
