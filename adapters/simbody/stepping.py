"""Simbody's stepping through OpenSim's ``Manager``: one integrator, advanced from sample to sample.

OpenSim 4.6's ``Manager`` wraps Simbody's eight integrators (``METHODS``; the adapter declares five,
``adapter.INTEGRATORS``) and a ``TimeStepper``. A run builds a
``Manager`` on the prepared model, sets the method and either a fixed step (``setIntegratorFixedStepSize``) or
the accuracy (``setIntegratorAccuracy``: Simbody's relative error tolerance, ``rtol``), initializes it from a
copy of the initial state and calls ``integrate(t_k)`` for each sample time ``t_k``: Simbody steps to each
sample exactly (a step that would pass it is shortened) and keeps its step size and statistics between calls.
The state's ``Y`` (q, u) is copied at each sample.

OpenSim logs a summary at every ``integrate`` (console and, by default, ``opensim.log``): its logger is off
(``model.engine``) and set to ``info`` only for the last call, whose summary, captured from the console's file
descriptor, gives Simbody's cumulative steps and realizations (``_statistics``); nothing reaches the user's
console or disk.

A run Simbody cannot finish (its step size underflows, a NaN state) raises in OpenSim; that is data: NaN from the
first sample not reached, the engine's message kept.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import sys
import time

import numpy as np

__all__ = ["METHODS", "simulate", "statistics_logged", "Console"]

# Simbody's integrators by the adapter's names, as OpenSim's ``Manager.IntegratorMethod_*`` names them.
METHODS = {
    "rk-merson": "RungeKuttaMerson", "rk-feldberg": "RungeKuttaFeldberg", "rk3": "RungeKutta3",
    "rk2": "RungeKutta2", "semi-explicit-euler2": "SemiExplicitEuler2", "verlet": "Verlet", "cpodes": "CPodes",
    "explicit-euler": "ExplicitEuler",
}
# OpenSim's summary lines (Manager.cpp, 4.6): cumulative counts since ``initialize``.
_STEPS = re.compile(r"number of steps taken / attempted:\s*(\d+)\s*/\s*(\d+)")
_REALIZATIONS = re.compile(r"number of realizations:\s*(\d+)")


@contextlib.contextmanager
def statistics_logged(osim):
    """OpenSim's logger at ``info`` for the block, off again after it (``model.engine`` switches it off: setting
    a level logs a line itself, so the block belongs inside a ``Console``)."""
    osim.Logger.setLevel(osim.Logger.Level_Info)
    try:
        yield
    finally:
        osim.Logger.setLevel(osim.Logger.Level_Off)


class Console:
    """File descriptor 1 (where OpenSim's console sink writes) captured in an anonymous in-memory file for the
    ``with`` block; ``text`` holds what was written."""

    def __enter__(self):
        sys.stdout.flush()
        _libc_flush()
        self._fd = os.memfd_create("opensim-console")
        self._saved = os.dup(1)
        os.dup2(self._fd, 1)
        self.text = ""
        return self

    def __exit__(self, *exc):
        _libc_flush()
        os.dup2(self._saved, 1)
        os.close(self._saved)
        size = os.fstat(self._fd).st_size
        self.text = os.pread(self._fd, size, 0).decode(errors="replace")
        os.close(self._fd)
        return False


def _libc_flush():
    """C's stdio buffers flushed (OpenSim's console sink writes through them)."""
    ctypes.CDLL(None).fflush(None)


def manager(p):
    """A ``Manager`` for prepared run ``p``: its method, and its fixed step or its accuracy, set."""
    model, settings = p.model, p.settings
    osim = model.osim
    mgr = osim.Manager(model.model)
    mgr.setIntegratorMethod(getattr(osim.Manager, "IntegratorMethod_" + METHODS[settings.integrator]))
    if settings.dt is not None:
        mgr.setIntegratorFixedStepSize(float(settings.dt))
    else:
        mgr.setIntegratorAccuracy(float(settings.rtol))
    return mgr


def simulate(p):
    """Integrate through ``p.times``: ``(Y (n, ny), wall s, steps, realizations, message)``, Simbody's state
    ``(q, u)`` at each sample, NaN from the first sample not reached or not finite; ``message``: OpenSim's error
    ("": none)."""
    model = p.model
    osim = model.osim
    times = p.times
    n = len(times)
    state = osim.State(model.state0)
    state.setTime(float(times[0]))
    Y = np.full((n, state.getNY()), np.nan)
    Y[0] = state.getY().to_numpy()
    mgr = manager(p)
    message, text, reached = "", "", 0
    mgr.initialize(state)
    start = time.perf_counter()
    try:
        for k in range(1, n):
            if k < n - 1:
                Y[k] = mgr.integrate(float(times[k])).getY().to_numpy()
            else:  # the last call logs Simbody's cumulative statistics, captured
                with Console() as console, statistics_logged(osim):
                    Y[k] = mgr.integrate(float(times[k])).getY().to_numpy()
                text = console.text
            reached = k
    except RuntimeError as e:  # Simbody gave up (step size underflow, NaN): data, not an error
        message = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
    wall = time.perf_counter() - start
    bad = ~np.all(np.isfinite(Y[:reached + 1]), axis=1)
    first = int(np.argmax(bad)) if bad.any() else (None if reached == n - 1 else reached + 1)
    if first is not None:
        Y[first:] = np.nan
    steps, realizations = _statistics(text, p, first)
    return Y, wall, steps, realizations, message


def _statistics(text, p, first):
    """Simbody's steps taken and realizations from OpenSim's last summary; where the run stopped early (no
    summary), the fixed-step count to the last sample reached and no realization count."""
    steps, real = _STEPS.findall(text), _REALIZATIONS.findall(text)
    if steps and real:
        return int(steps[-1][0]), int(real[-1])
    reached = p.times[(first if first is not None else len(p.times)) - 1] - p.times[0]
    count = int(round(reached / p.settings.dt)) if p.settings.dt is not None else 0
    return count, count
