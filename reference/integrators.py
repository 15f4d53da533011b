"""Time integrators of the reference solver, chosen by name.

Contract (every integrator, like scipy's ``OdeSolver`` family):

1. is registered under a lowercase, hyphenated ``name`` with ``@integrator``;
2. says whether it is ``fixed_step`` (knob: ``dt``, which must divide every
   sample interval) or adaptive (knobs: ``rtol``, ``atol``) and which
   ``options`` it accepts — anything else raises before the run starts;
3. ``run(system, times, settings)`` integrates a ``System`` from ``times[0]``
   and returns the state exactly at every sample time: ``Q (n, nq)``,
   ``V (n, nv)`` and a ``Stats`` (steps, right-hand-side evaluations);
4. evaluates the right-hand side at every stage (loads included), so its
   order of accuracy is the method's own;
5. stops early when the state becomes non-finite and fills the remaining
   samples with NaN (divergence is a result, not an exception).

A ``System`` provides ``blocks`` (see ``configuration``), ``q0 (nq,)``,
``v0 (nv,)`` and ``acceleration(t, q, v) -> (nv,)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.registry import Registry
from dalembert.settings import is_numerical_failure, knob_problems, steps_per_interval
from dalembert.stepping import march
from dalembert.reference import configuration as cfg

__all__ = ["INTEGRATORS", "integrator", "Stats", "check_settings", "steps_per_interval", "MAX_STEPS_PER_INTERVAL",
           "first_order"]

INTEGRATORS = Registry("integrator")

# A constrained system's adaptive run (``_SolveIVP._run_projected``) takes at most this many steps per
# sample interval. Measured on the four-bar over 1 s (sample interval 0.01 s): at most 2 per interval for
# DOP853 at rtol = 1e-6 to 1e-12, 6 and 20 for LSODA at 1e-6 and 1e-9; near a singular position at 1e-12
# both shrink their steps without end (DOP853 spent ~70000 evaluations, 230 s, before scipy gave up).
# 200 is 10 times the most a finishing interval took, and bounds a stalled interval at a few thousand
# evaluations.
MAX_STEPS_PER_INTERVAL = 200


@dataclass(frozen=True)
class Stats:
    """What an integration cost: steps, right-hand-side evaluations, and ``message``: why it stopped
    early (empty when it reached the end or when its state became non-finite)."""

    n_steps: int
    n_rhs: int
    message: str = ""


def integrator(name):
    """Register an integrator class under ``name``."""

    def register(cls):
        cls.name = name
        INTEGRATORS.register(name, cls)
        return cls

    return register


def check_settings(settings, times):
    """Raise ValueError naming the field if ``settings`` do not fit the integrator."""
    cls = INTEGRATORS[settings.integrator]
    problems = knob_problems(settings, repr(cls.name), cls.fixed_step, cls.options, times)
    if problems:
        raise ValueError("; ".join(problems))


class _FixedStep:
    """Shared driver: ``step`` from sample to sample in ``dt`` substeps."""

    fixed_step = True
    options = ()
    stages = 1

    def run(self, system, times, settings):
        counts = steps_per_interval(np.asarray(times, dtype=float), settings.dt)
        project = getattr(system, "project", None)  # a constrained system: back onto its manifolds after each step
        if project is None:
            step = lambda t, q, v, h: self.step(system, t, q, v, h)  # noqa: E731
        else:
            step = lambda t, q, v, h: project(*self.step(system, t, q, v, h))  # noqa: E731
        Q, V, steps = march(step, system.q0, system.v0, times, counts)
        return Q, V, Stats(steps, steps * self.stages)


@integrator("euler")
class SymplecticEuler(_FixedStep):
    """Semi-implicit (symplectic) Euler on the group: velocity first, then
    ``q <- q exp(h v_new)``. First order."""

    stages = 1

    def step(self, s, t, q, v, h):
        v = v + h * s.acceleration(t, q, v)
        return cfg.retract(s.blocks, q, h * v), v


@integrator("rk4")
class ClassicalRK4(_FixedStep):
    """Classical fourth-order Runge-Kutta on the embedded coordinates (quaternion or
    rotation matrix as plain numbers). Quaternion norm / orthonormality drift as O(h^4)."""

    stages = 4

    def step(self, s, t, q, v, h):
        f = lambda t, q, v: (cfg.qdot(s.blocks, q, v), s.acceleration(t, q, v))  # noqa: E731
        k1q, k1v = f(t, q, v)
        k2q, k2v = f(t + h / 2, q + h / 2 * k1q, v + h / 2 * k1v)
        k3q, k3v = f(t + h / 2, q + h / 2 * k2q, v + h / 2 * k2v)
        k4q, k4v = f(t + h, q + h * k3q, v + h * k3v)
        return (q + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q),
                v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v))


@integrator("rkmk4")
class MuntheKaasRK4(_FixedStep):
    """Runge-Kutta-Munthe-Kaas with the classical RK4 tableau (Munthe-Kaas,
    BIT 38, 1998): stages in the tangent space at ``q``, corrected by the exact
    ``dexp^-1`` of SO(3), configuration advanced by the exponential. Fourth
    order, and the attitude stays on the group to roundoff."""

    stages = 4

    def step(self, s, t, q, v, h):
        b = s.blocks

        def f(tc, theta, vel):
            qs = cfg.retract(b, q, theta)
            return cfg.dexpinv(b, theta, vel), s.acceleration(tc, qs, vel)

        zero = np.zeros_like(v)
        k1q, k1v = f(t, zero, v)
        k2q, k2v = f(t + h / 2, h / 2 * k1q, v + h / 2 * k1v)
        k3q, k3v = f(t + h / 2, h / 2 * k2q, v + h / 2 * k2v)
        k4q, k4v = f(t + h, h * k3q, v + h * k3v)
        theta = h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        return cfg.retract(b, q, theta), v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)


def first_order(system):
    """``system`` as a first-order problem on the embedded state ``y = (q, v)``: ``nq``, the right-hand side
    ``rhs(t, y) -> y'`` (``(q', v')``, q' through the blocks' kinematics) and the initial state ``y0``."""
    nq, b = len(system.q0), system.blocks

    def rhs(t, y):
        q, v = y[:nq], y[nq:]
        return np.concatenate([cfg.qdot(b, q, v), system.acceleration(t, q, v)])

    return nq, rhs, np.concatenate([system.q0, system.v0]).astype(float)


class _SolveIVP:
    """An adaptive method of scipy's ``solve_ivp`` on the embedded coordinates, sampled by its
    dense output at the sample times."""

    fixed_step = False
    options = ()
    method = ""

    @classmethod
    def stepper(cls):
        """scipy's stepper class of ``method`` (``scipy.integrate.DOP853``, ``LSODA``, ``Radau``), imported here: the
        ``_run_projected`` path steps it itself."""
        from scipy import integrate  # lazily: scipy.integrate is ~0.3 s of a process's start

        return getattr(integrate, cls.method)

    @staticmethod
    def _problem(system, times, settings):
        """The first-order problem on ``y = (q, v)``: ``nq``, the right-hand side, ``y0``, the sampled
        states ``Y`` (NaN until reached) and the tolerances."""
        nq, rhs, y0 = first_order(system)
        Y = np.full((len(times), len(y0)), np.nan)
        return nq, rhs, y0, Y, dict(rtol=settings.rtol or DOP853.TRUTH_RTOL, atol=settings.atol or DOP853.TRUTH_ATOL)

    def run(self, system, times, settings):
        nq, rhs, y0, Y, tols = self._problem(system, times, settings)
        project = getattr(system, "project", None)
        if project is not None:  # a constrained system: integrate sample to sample, projecting at each
            return self._run_projected(rhs, project, nq, times, y0, Y, tols)
        from scipy.integrate import solve_ivp  # here, not at the top: scipy.integrate is ~0.3 s of a process's start

        try:
            sol = solve_ivp(rhs, (times[0], times[-1]), y0, method=self.method, t_eval=times, **tols)
        except Exception as e:  # a blown-up state: NaN (contract item 5)
            if not is_numerical_failure(e):
                raise
            return Y[:, :nq], Y[:, nq:], Stats(0, 0)
        Y[: sol.y.shape[1]] = sol.y.T
        return Y[:, :nq], Y[:, nq:], Stats(self.steps(sol), int(sol.nfev))

    def _run_projected(self, rhs, project, nq, times, y0, Y, tols):
        """One solve per sample interval, each started from the previous sample projected onto the
        constraint manifolds (``system.project``): the drift of an index-1 system stays that of one
        interval. The first sample is the initial state itself.

        scipy's solver is stepped here, not called through ``solve_ivp``, so that an interval that
        takes more than ``MAX_STEPS_PER_INTERVAL`` steps (its step size collapsing, e.g. near a
        singular position of a loop, ``reference.loops``) ends the run after a bounded number of
        steps: NaN from that sample on (contract item 5), and ``Stats.message`` says where and why."""
        Y[0] = y = y0
        steps = nfev = 0
        message = ""
        stepper = self.stepper()
        for k in range(len(times) - 1):
            try:
                with np.errstate(over="ignore", invalid="ignore"):
                    solver = stepper(rhs, times[k], y, times[k + 1], **tols)
                    taken, failure = 0, None
                    while solver.status == "running" and taken < MAX_STEPS_PER_INTERVAL:
                        failure = solver.step()  # scipy returns its message when the step fails (else None)
                        taken += 1
                    steps, nfev = steps + taken, nfev + int(solver.nfev)
                    if solver.status != "finished":
                        message = self._stalled(solver, times[k], times[k + 1], taken, failure)
                        break
                    q, v = project(solver.y[:nq], solver.y[nq:])
            except Exception as e:  # a blown-up state: NaN from here on (contract item 5)
                if not is_numerical_failure(e):
                    raise
                break
            y = np.concatenate([q, v])
            if not np.all(np.isfinite(y)):
                break
            Y[k + 1] = y
        return Y[:, :nq], Y[:, nq:], Stats(steps, nfev, message)

    def _stalled(self, solver, t0, t1, taken, failure):
        """Why the interval ``[t0, t1]`` (s) did not finish: scipy's own failure (``failure``, the message its
        last ``step()`` returned; its solvers keep none), or the step cap."""
        last = "none taken" if solver.step_size is None else f"{solver.step_size:.3g} s"  # None before its first step
        where = (f"{self.name} stopped at t = {solver.t:.10g} s in the sample interval [{t0:g}, {t1:g}] s after "
                 f"{taken} steps (last step {last})")
        if solver.status == "failed":
            return f"{where}: {failure}"
        return (f"{where}: more than MAX_STEPS_PER_INTERVAL = {MAX_STEPS_PER_INTERVAL} steps, its step size "
                "collapsing (near a singular position of a closed loop the projected right-hand side cannot meet "
                "the tolerance)")


@integrator("dop853")
class DOP853(_SolveIVP):
    """scipy's adaptive Dormand-Prince 8(5,3) on the embedded coordinates, with
    its dense output at the sample times. The truth where no closed form exists
    (at ``TRUTH_RTOL``/``TRUTH_ATOL``)."""

    method = "DOP853"
    # Defaults when the settings give no tolerance; tight enough to serve as truth
    # (errors ~1e-12 on the canonical cases), loose enough to finish in seconds.
    TRUTH_RTOL = 1e-12
    TRUTH_ATOL = 1e-12

    @staticmethod
    def steps(sol):
        return int(max(0, (sol.nfev - 1) // 12))  # DOP853: 12 evaluations per step


@integrator("lsoda")
class LSODA(_SolveIVP):
    """scipy's LSODA (ODEPACK: Adams multistep methods up to order 12, switching to BDF when the
    problem turns stiff), with its dense output at the sample times: a second integrator of
    another family than the truth's one-step DOP853, to check it (``dalembert.testing``)."""

    method = "LSODA"

    @staticmethod
    def steps(sol):
        return int(sol.nfev)  # multistep: about one evaluation per step (corrector iterations aside)


@integrator("radau")
class Radau(_SolveIVP):
    """scipy's Radau IIA (implicit Runge-Kutta of order 5, L-stable; Jacobians by finite differences) on the
    embedded coordinates, with its dense output at the sample times: the truth of stiff scenes
    (``solver.truth_settings``), where DOP853's explicit steps are held to its stability bound.
    Measured on ``flyball_governor`` over 1 s at rtol = atol = 1e-12: within 3.1e-13 (coordinates) and
    1.3e-12 (rates) of DOP853 at 1e-12, with 10729 evaluations against DOP853's 47513."""

    method = "Radau"

    def run(self, system, times, settings):
        if getattr(system, "project", None) is not None:  # constrained: stepped per interval (steps counted there)
            return super().run(system, times, settings)
        nq, rhs, y0, Y, tols = self._problem(system, times, settings)
        from scipy.integrate import solve_ivp  # lazily, as in _SolveIVP.run

        try:  # dense output rather than t_eval: the same interpolants, and the steps are then known
            sol = solve_ivp(rhs, (times[0], times[-1]), y0, method=self.method, dense_output=True, **tols)
        except Exception as e:  # a blown-up state: NaN (contract item 5)
            if not is_numerical_failure(e):
                raise
            return Y[:, :nq], Y[:, nq:], Stats(0, 0)
        reached = times <= sol.t[-1]
        Y[reached] = sol.sol(times[reached]).T
        Y[0] = y0  # (the initial state itself, not its interpolant)
        return Y[:, :nq], Y[:, nq:], Stats(len(sol.t) - 1, int(sol.nfev), "" if sol.success else sol.message)
