"""DART's stepping: ``World.step`` from sample to sample, its loads, and where it diverges.

DART 6.20 has one time integrator, semi-implicit Euler (``World.step``: forward dynamics at the step's start,
``Skeleton.integrateVelocities``, the constraint solver, then ``integratePositions`` from the new velocities),
at a fixed step, with no error control. Each step is a ``World.step(False)``: ``False`` keeps the external forces
(DART's default, ``True``, clears them after every step).

Loads (``apply_loads``) are DART's external force and torque on the body, which DART keeps in body axes at a
point of the body: a follower load is set once, in body axes, and stays the scene's exactly; a world-frame
load is set again before every step from the pose at the step's start (where the semi-implicit Euler step
evaluates its forces), its force and point given in world and body axes and turned into body axes by DART.

A blow-up is data: the first sample whose state is not finite ends the run, NaN from there on. DART also detects
one itself and hides it: on a non-finite acceleration or transmitted force it warns on the console ("Non-finite
joint accelerations detected ... Setting accelerations to zero to avoid instability") and steps on with a finite,
wrong state. Its console (``std::cerr``, file descriptor 2) is therefore captured while it steps and reads back
(``EngineLog``: the adapter prints nothing), checked after every sample interval, and a "Non-finite" warning is the
engine's own detection of a divergence: NaN from that sample on, DART's message kept.

``p`` is the ``DartPrepared`` that ``DartAdapter.prepare`` returns.
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

__all__ = ["simulate", "apply_loads", "plain", "EngineLog", "DIVERGED"]

# DART's warning on a non-finite acceleration or transmitted force (BodyNode.cpp, GenericJoint.hpp in 6.20).
DIVERGED = "Non-finite"
# Steps between two looks at DART's console for its non-finite warning (a look, one fstat, costs about a step):
# a blow-up's warnings (~300 bytes a step) stay under ~60 kB before the loop stops, and the looks add <~1 %.
POLL_STEPS = 200
# The most of DART's console text kept per run (its warnings repeat every step once a state has blown up).
LOG_KEEP_CHARS = 4000


class EngineLog:
    """DART's console (file descriptor 2, where ``std::cerr`` writes) captured in an anonymous in-memory file for
    the duration of a ``with`` block, so that nothing reaches the user's console; ``grew()`` says whether DART
    wrote since the last call, ``text`` holds what it wrote (the first ``LOG_KEEP_CHARS``) after the block."""

    def __enter__(self):
        sys.stderr.flush()
        self._fd = os.memfd_create("dart-console") if hasattr(os, "memfd_create") else _anonymous_file()
        self._saved = os.dup(2)
        os.dup2(self._fd, 2)
        self._size = 0
        self.text = ""
        return self

    def grew(self):
        """Whether DART wrote since the last call: the captured file's size (one ``fstat``, no read)."""
        size = os.fstat(self._fd).st_size
        grew, self._size = size != self._size, size
        return grew

    def read(self):
        """What DART has written so far (the first ``LOG_KEEP_CHARS``)."""
        return os.pread(self._fd, LOG_KEEP_CHARS, 0).decode(errors="replace")

    def __exit__(self, *exc):
        sys.stderr.flush()
        os.dup2(self._saved, 2)
        os.close(self._saved)
        self.text = self.read()
        os.close(self._fd)
        return False


def _anonymous_file():
    """A file descriptor of an unnamed temporary file (where ``memfd_create`` is missing)."""
    import tempfile

    f = tempfile.TemporaryFile()
    fd = os.dup(f.fileno())
    f.close()
    return fd


def apply_loads(model):
    """Every scene load as its body's external force and torque in DART, from the current pose."""
    touched = {ld.body for ld in model.scene.loads}
    for name in touched:
        model.nodes[name].clearExternalForces()
    for ld in model.scene.loads:
        node, local = model.nodes[ld.body], ld.frame == "body"
        vector = np.asarray(ld.vector, dtype=float)
        if ld.kind == "force":
            node.addExtForce(vector, np.asarray(ld.point, dtype=float), local, True)
        else:
            node.addExtTorque(vector, local)


def simulate(p):
    """Step through ``p.times``: ``(Q (n, ndofs), V (n, ndofs), wall s, steps, message)``, the skeleton's
    positions and velocities at each sample (DART's coordinates), NaN from the first sample whose state is not
    finite or whose interval DART flagged non-finite (``DIVERGED``); ``message`` is DART's console text ("": none).

    DART's console is looked at once every ``POLL_STEPS`` steps (a look costs as much as a step); where DART
    flagged a blow-up, the run is repeated looking at it after every sample interval, to find the first sample
    flagged (the stepping is deterministic), and that run's time is the one reported.
    """
    with EngineLog() as log:
        Q, V, wall, taken, flagged = _march(p, log, POLL_STEPS)
    if flagged:
        with EngineLog() as log:
            Q, V, wall, taken, flagged = _march(p, log, 0)
    return Q, V, wall, taken, plain(log.text)


def plain(text):
    """DART's console text as a run's message: its first warning, without the terminal's colour codes, and how
    many more lines it wrote within the first ``LOG_KEEP_CHARS`` ("": nothing)."""
    import re

    lines = [line.strip() for line in re.sub(r"\x1b\[[0-9;]*m", "", text).splitlines() if line.strip()]
    if len(lines) <= 1:
        return "".join(lines)
    return f"{lines[0]} (and {len(lines) - 1} more lines, the first {LOG_KEEP_CHARS} characters read)"


def _march(p, log, poll_steps):
    """The stepping loop; per sample interval only the state's copies, and DART's console looked at (one
    ``fstat``) once ``poll_steps`` steps have passed since the last look (0: every interval); the samples are
    tested finite at once after the loop (a test per sample cost ~10 us, several steps). A state that turns
    non-finite makes DART warn, which ends the loop. Returns ``(Q, V, wall, steps, flagged)``."""
    model = p.model
    world, skeleton = model.world, model.skeleton
    model.reset()
    apply_loads(model)
    every_step = any(ld.frame == "world" for ld in model.scene.loads)  # world loads turn in body axes
    n = len(p.times)
    Q, V = np.full((n, len(model.q0)), np.nan), np.full((n, len(model.v0)), np.nan)
    Q[0], V[0] = model.q0, model.v0
    step, positions, velocities, grew = world.step, skeleton.getPositions, skeleton.getVelocities, log.grew
    counts = [int(c) for c in p.steps]
    flagged, since = None, 0
    start = time.perf_counter()
    for k, nstep in enumerate(counts, 1):
        if every_step:
            for _ in range(nstep):
                apply_loads(model)
                step(False)
        else:
            for _ in range(nstep):
                step(False)
        Q[k], V[k] = positions(), velocities()
        since += nstep
        if since >= poll_steps or k == n - 1:
            since = 0
            if grew() and DIVERGED in log.read():
                flagged = k
                break
    wall = time.perf_counter() - start
    reached = flagged if flagged is not None else n - 1
    bad = ~(np.all(np.isfinite(Q[:reached + 1]), axis=1) & np.all(np.isfinite(V[:reached + 1]), axis=1))
    first = int(np.argmax(bad)) if bad.any() else flagged
    if first is not None:
        Q[first:], V[first:] = np.nan, np.nan
    return Q, V, wall, int(sum(counts[:reached])), flagged is not None
