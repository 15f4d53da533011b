"""Sampling an Exudyn solve at the case's times, and stopping one that cannot go on.

Output stays in memory: no solution file. Exudyn's sensors are stored in memory
and read back at the sample times (``solve``, ``stored_samples``); where its
sensor schedule misses a sample, the solve is repeated with every sample read
from Python (``_Sampler``).

The adaptive solvers are driven sample by sample (``solve_per_sample``:
``MainSolverExplicit.SolveSteps`` with the end time set to the next sample,
which Exudyn's step control lands on exactly), so their steps never exceed the
sample interval: Exudyn has no dense output, and sampling at fixed times caps the
step. The solver is not restarted at a sample: its step-size control carries over
(measured, dopri5 at rtol 1e-12 on the pendulum: the first attempt after each 0.01-s
sample is the controller's ~4e-3 s, not the 0.01-s initial step; 12 rejected attempts
over 100 samples). Where the error of a step of the sample interval already meets a
tolerance, that tolerance changes nothing (measured over 1 s at 0.01-s samples: dopri5
on the pendulum takes 100 steps, 5.82e-11 rad, at every rtol from 1e-4 to 1e-8, and 112
steps at 1e-9; on the torque-free top 100 steps, 4.48e-12 rad, from 1e-4 to 1e-10): the
runs are the cap's, and the report says so (``reports.findings``: "a tolerance changed
nothing").
``_Guard`` stops an adaptive solve that would retry one step without end.
Steps are counted as Exudyn takes them (``steps_taken``), so steps Exudyn
shrinks on Newton failure are counted.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dalembert.adapters.exudyn import compat

__all__ = ["Solved", "solve", "solve_per_sample", "stored_samples", "steps_taken", "MIN_STEP_FRACTION",
           "MAX_REJECTIONS_IN_A_ROW", "SCHEDULE_LEAD", "ON_TIME"]

# Adaptive solvers stop (the run is stored as failed, with the time reached) when a step
# would fall below this fraction of the sample interval: such a step means the solver is
# stuck (measured: ode23 on Tait-Bryan nodes at their singularity on the 50 rad/s fast spin
# shrinks its steps without end); the hard cases need no step below ~1e-3 of the interval.
MIN_STEP_FRACTION = 1e-6
# Adaptive solvers also stop after this many rejected attempts in a row at one time: Exudyn
# retries a rejected step without end once it sits at its minimum step (measured: ode23 at
# rtol 1e-9 on Tait-Bryan nodes at their singularity, t = 0.314 s on the intermediate-axis
# top, 1.2e7 attempts in a minute); a controller that shrinks the step on each rejection
# reaches any step it could accept in far fewer.
MAX_REJECTIONS_IN_A_ROW = 100
# Fixed-step runs are sampled by Exudyn's sensor schedule, shortened so that it leads the
# sample times by this many steps at the horizon: enough to stay ahead of the ulps its
# accumulated time loses (measured: 2e-8 s behind after 1e6 steps of 1e-3 s, i.e. 2e-5
# steps: 500x, and 5x at the matrix's 1e8-step limit if the loss grows linearly), and short of
# the steps Exudyn shrinks to when Newton fails (halvings of dt: measured down to dt / 64 on the
# heavy top at dt = 1e-2), so each write is still the step that lands on its sample. (A lead of
# 0.25 steps wrote one shrunk step early there, and every such run solved twice.)
SCHEDULE_LEAD = 1e-2
# A fixed-step sample is read at the step that lands on its time to within this fraction of a
# step (Exudyn's accumulated time is off by 2e-5 steps after 1e6 steps). Exudyn shrinks
# implicit steps when Newton fails, and its grid is then lost: a sample no step lands on ends
# the run (no dense output to interpolate; reading the nearest step would shift the sample).
ON_TIME = 1e-3


@dataclass(frozen=True)
class Solved:
    """One solve of a prepared system (what ``solve`` returns).

    Attributes
    ----------
    values : dict (sensor group, quantity) -> ndarray (n, width) or list of rows — the samples
    read : int — samples read
    late : str or None — why Exudyn's stored sensors missed a sample, or None
    it : Exudyn's solver iteration record, or None
    error : Exception or None — what Exudyn raised
    wall : float — the solve's wall time, s
    steps : int — steps taken
    stalled : str or None — why the guard or the Python sampler stopped the solve
    sampling : str — how it was sampled, in words
    reached : float — the time reached, s
    """

    values: dict
    read: int
    late: str | None
    it: object
    error: Exception | None
    wall: float
    steps: int
    stalled: str | None
    sampling: str
    reached: float


def solve(mbs, sensors, settings, times, dt=None, stored=True):
    """One solve of the assembled system ``mbs``, sampled at ``times`` by Exudyn or from Python.

    ``stored``: Exudyn keeps the sensors in memory, with no Python per step or sample.
    Fixed-step solvers write on Exudyn's schedule, which fires when its accumulated time
    passes its accumulated schedule; both lose ulps over many steps (measured: every sample
    one step late after 3e5 steps of 1e-3 s at the exact interval), so the schedule is
    shortened to lead the samples by ``SCHEDULE_LEAD`` steps at the horizon, still the step
    nearest each sample. Adaptive solvers run one ``SolveSteps`` per sample interval, each
    ending on its sample, where Exudyn writes the sensors (the schedule is set beyond the
    horizon, so it writes nowhere else). The time column is then checked against the
    samples, and ``late`` names the first miss. Otherwise ``_Sampler`` reads from Python.

    Parameters
    ----------
    mbs : exudyn.MainSystem, assembled
    sensors : dict — body (or ``__q``, ``__v``, ``__joint:<child>``) -> quantity -> sensor number
    settings : exudyn.SimulationSettings — the solver's (named by ``compat.set_solver``)
    times : ndarray (n,) — sample times, s
    dt : float or None — the fixed step, s; None for an adaptive (explicit) solver
    stored : bool — Exudyn's stored sensors, or ``_Sampler``

    Returns
    -------
    Solved — the samples, how many were read and how, and what the solver reported
    """
    import exudyn as exu

    adaptive = dt is None
    interval, horizon = float(times[1] - times[0]), float(times[-1] - times[0])
    min_step = settings.timeIntegration.minimumStepSize if adaptive else None
    tol = ON_TIME * (min_step if adaptive else dt)  # a sample is on time within this, s
    flat = [(body, key, sid) for body, group in sensors.items() for key, sid in group.items()]
    sampler = None
    for _, _, sid in flat:  # (set either way: the system may have been solved the other way before)
        mbs.SetSensorParameter(sid, "storeInternal", stored)
    if stored:
        compat.set_sensors_write_period(
            settings, 2.0 * horizon if adaptive else interval * (1.0 - SCHEDULE_LEAD * dt / horizon))
    else:
        sampler = _Sampler(mbs, flat, times, None if adaptive else tol)
    guard = _Guard(mbs, min_step) if adaptive else None
    solver = exu.MainSolverExplicit() if adaptive else None
    error = None
    start = time.perf_counter()
    try:
        if adaptive:
            solve_per_sample(solver, mbs, settings, times, tol, sampler)
        else:
            mbs.SolveDynamic(settings, solverType=compat.solver_of(settings))
    except Exception as e:  # Exudyn raises on solver failure; what was sampled so far is kept
        error = e
    wall = time.perf_counter() - start
    it = solver.it if adaptive else mbs.sys["dynamicSolver"].it if "dynamicSolver" in mbs.sys else None
    late = None
    if stored:
        values, read, late = stored_samples(mbs, flat, times, tol, error)
    else:
        values, read = sampler.values, sampler.next
    stalled = guard.stalled if guard else sampler.stalled if sampler else None
    return Solved(values=values, read=read, late=late, it=it, error=error, wall=wall,
                  steps=steps_taken(it), stalled=stalled, sampling="Exudyn's stored sensors",
                  reached=float(it.currentTime) if it is not None else float(times[max(read, 1) - 1]))


def stored_samples(mbs, flat, times, tol, error):
    """The stored rows at the sample times: (values, samples read, first miss or None)."""
    stored = {}
    for body, key, sid in flat:
        data = np.asarray(mbs.GetSensorStoredData(sid), dtype=float)
        stored[(body, key)] = data if data.ndim == 2 else np.empty((0, 1))
    # every sensor is written at the same steps: one time column speaks for all; extra rows
    # (written between samples, or at the horizon again) are ignored
    t = next(iter(stored.values()))[:, 0]
    rows = np.minimum(np.searchsorted(t, times - tol), max(len(t) - 1, 0))
    on_time = np.abs(t[rows] - times) <= tol if len(t) else np.zeros(len(times), bool)
    read = len(times) if on_time.all() else int(np.argmin(on_time))
    late = None
    if read < len(times) and (error is None or (len(t) and t[-1] > times[read])):
        late = (f"Exudyn's stored sensors have no row at sample {read} (t = {times[read]:.12g} s), the "
                f"nearest at {t[rows[read]]:.12g} s" if len(t) else "Exudyn stored no sensor rows")
    return {k: v[rows[:read], 1:] for k, v in stored.items()}, read, late


def solve_per_sample(solver, mbs, settings, times, tol, sampler=None):
    """Adaptive explicit solvers: one ``SolveSteps`` per sample interval, ending on the sample."""
    solver.InitializeSolver(mbs, settings)
    if sampler is not None:  # sample 0 once the solver has set the initial state (a system solved before
        sampler.read(0)  # holds the last solve's end until then)
    try:
        for k in range(1, len(times)):
            solver.it.endTime = float(times[k])
            solver.SolveSteps(mbs, settings)
            if solver.it.currentTime < times[k] - tol:
                break  # the solver gave up (step size below its minimum): the run is incomplete
            if sampler is not None:
                sampler.read(k)
    finally:
        solver.FinalizeSolver(mbs, settings)


def steps_taken(it):
    """Accepted steps of a solve: Exudyn counts one discontinuous iteration per step where nothing
    switches (no scene here has contacts or switches); ``currentStepIndex`` restarts with each
    ``SolveSteps``. A last step of a few ulps, taken when the accumulated time ends short of the
    horizon, counts."""
    return int(it.discontinuousIterationsCount) if it is not None else 0


class _Stuck(RuntimeError):
    """An adaptive run that retries one step without end."""


class _Guard:
    """Stops an adaptive solve where Exudyn would go on forever: at a step of ``min_step``, or
    after ``MAX_REJECTIONS_IN_A_ROW`` attempts at one time.

    Installed as the pre-step user function, which Exudyn calls before every attempt, rejected
    ones included, with the attempt's END time: the same time again is a retry of the same step
    (rejected at the minimum step); a time just past the last one is a step of the minimum.
    Returning False does not stop Exudyn there, raising does (what was sampled so far is kept).
    """

    def __init__(self, mbs, min_step):
        self.min_step, self.stalled, self.last_time, self.attempts = min_step, None, None, 0
        mbs.SetPreStepUserFunction(self._pre_step)

    def _pre_step(self, mbs, t):
        if t == self.last_time:
            self.attempts += 1
            if self.attempts > MAX_REJECTIONS_IN_A_ROW:
                self.stalled = f"stuck: {MAX_REJECTIONS_IN_A_ROW} rejected attempts in a row at t = {t:g} s"
                raise _Stuck(self.stalled)
            return True
        if self.last_time is not None and 0.0 < t - self.last_time <= self.min_step * (1.0 + 1e-9):
            self.stalled = f"stuck: the adaptive step fell to its minimum {self.min_step:g} s"
            raise _Stuck(self.stalled)
        self.last_time, self.attempts = t, 1
        return True


class _Sampler:
    """Reads every sensor at the sample times from Python (when Exudyn's stored sensors miss one).

    With ``tol`` (fixed-step solvers) it is the post-step user function and reads at the step
    that lands on each sample time to within ``tol`` s; a sample passed without landing stops
    the run. Without (adaptive solvers), ``read`` is called after each ``SolveSteps``. Sample 0
    is the initial state: read again once the solver has set it (at ``times[0]`` before the first step;
    after ``InitializeSolver``), as a system solved before holds the last solve's end until then.
    """

    def __init__(self, mbs, flat, times, tol=None):
        self.mbs, self.flat, self.times, self.tol, self.stalled = mbs, flat, times, tol, None
        self.values = {(body, key): [None] * len(times) for body, key, _ in flat}
        self.last_time, self.next = float(times[0]), 1
        self.read(0)
        if tol is not None:
            mbs.SetPostStepUserFunction(self._post_step)

    def read(self, k):
        for body, key, sid in self.flat:
            self.values[(body, key)][k] = np.array(self.mbs.GetSensorValues(sid), dtype=float)
        self.next = k + 1

    def _post_step(self, mbs, t):
        if t == self.times[0]:  # once before the first step, with accelerations and constraint
            self.read(0)  # forces of the initial state computed (not yet at assembly)
            return True
        if t > self.last_time:  # Exudyn also calls this once per solve without stepping
            self.last_time = t
            k = self.next
            if k < len(self.times):
                if abs(t - self.times[k]) <= self.tol:
                    self.read(k)
                elif t > self.times[k]:
                    self.stalled = (f"no step landed on sample {k} at t = {self.times[k]:g} s (Exudyn shrank its "
                                    f"steps after a Newton failure, so its grid is lost; the step went to t = {t:.9g} s)")
                    return False
        return True
