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
    finite or whose interval DART flagged non-finite (``DIVERGED``); ``message`` is DART's console text ("": none)."""
    with EngineLog() as log:
        Q, V, wall, taken = _march(p, log)
    return Q, V, wall, taken, plain(log.text)


def plain(text):
    """DART's console text without its terminal colour codes, stripped."""
    import re

    return re.sub(r"\x1b\[[0-9;]*m", "", text).strip()


def _march(p, log):
    model = p.model
    world, skeleton = model.world, model.skeleton
    model.reset()
    apply_loads(model)
    every_step = any(ld.frame == "world" for ld in model.scene.loads)  # world loads turn in body axes
    n = len(p.times)
    Q, V = np.full((n, len(model.q0)), np.nan), np.full((n, len(model.v0)), np.nan)
    Q[0], V[0] = model.q0, model.v0
    step = world.step
    taken = 0
    start = time.perf_counter()
    for k, nstep in enumerate(p.steps, 1):
        if every_step:
            for _ in range(nstep):
                apply_loads(model)
                step(False)
        else:
            for _ in range(nstep):
                step(False)
        taken += int(nstep)
        q, v = skeleton.getPositions(), skeleton.getVelocities()
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))) or (log.grew() and DIVERGED in log.read()):
            break
        Q[k], V[k] = q, v
    wall = time.perf_counter() - start
    return Q, V, wall, taken
