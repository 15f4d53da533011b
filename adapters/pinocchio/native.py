"""The Pinocchio adapter's fixed-step loop, compiled: ``stepper.cpp``.

A Python loop around Pinocchio's C++ calls costs 6-9x the calls themselves
(``python -m benchmarks.pinocchio``), so the work-precision diagrams would
measure Python, not Pinocchio. The same integrators, loads and spring-dampers in C++ against the
installed Pinocchio (headers and library from the ``pin`` wheel, Eigen from
``cmeel-eigen``) give the same numbers (tests/test_pinocchio.py) without a
Python call per step.

Built on first use (``make`` builds it at setup: ``python -m dalembert.adapters.pinocchio.native``)
with the system's C++ compiler into a cache keyed by the source, the compiler
flags and the Pinocchio version; where it cannot be built the adapter falls back
to its Python loop and says why in the run's audit. A compile that failed is remembered
under the same key (``<library>.failed``: the compiler's error), so that every later worker
falls back at once, naming the error and the file to delete to try again, instead of
compiling for minutes to fail again (as against Pinocchio 4.0.0's headers).

    python -m dalembert.adapters.pinocchio.native     # build (or find) the library; print where, or why not
"""

from __future__ import annotations

import ctypes
import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import sys

import numpy as np

from dalembert.adapters.pinocchio import springs
from dalembert.cache import cache_dir

__all__ = ["library", "NativeModel", "METHODS", "FAILED"]

SOURCE = os.path.join(os.path.dirname(__file__), "stepper.cpp")
METHODS = {"euler": 0, "rk4": 1, "rk4-naive": 2}
# Pinocchio's own compile definitions for its users (lib/cmake/pinocchio/pinocchioTargets.cmake,
# targets pinocchio_headers and pinocchio_default): Boost.MPL sizes its joint variant needs, and
# the explicit template instantiations the library ships (much shorter builds).
DEFINES = ["BOOST_MPL_LIMIT_LIST_SIZE=30", "BOOST_MPL_LIMIT_VECTOR_SIZE=30", "BOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
           "BOOST_FUSION_INVOKE_MAX_ARITY=12", "PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION", "NDEBUG"]
# -O2 and no -march: the same IEEE arithmetic as numpy's (no fused multiply-add), so the
# compiled and the Python loops agree to roundoff.
FLAGS = ["-O2", "-std=c++17", "-shared", "-fPIC"]
_ERR_LEN = 512
# A failed compile's marker beside the library it would have been (same key): what failed, remembered.
FAILED = ".failed"
# How many of a failed compile's error lines its reason quotes (the first name the cause; the rest follow from it).
ERROR_LINES = 5
_cached = {}


def _paths():
    import pinocchio

    # the pin wheel: cmeel.prefix/lib/python3.x/site-packages/pinocchio, headers in cmeel.prefix/include
    prefix = os.path.abspath(os.path.join(os.path.dirname(pinocchio.__file__), *[".."] * 4))
    if not os.path.isdir(os.path.join(prefix, "include", "pinocchio")):
        raise RuntimeError(f"no Pinocchio headers under {prefix}/include (not the pin wheel's layout)")
    return prefix, pinocchio.__version__


def _command(prefix, out):
    cxx = os.environ.get("CXX") or shutil.which("c++") or shutil.which("g++") or shutil.which("clang++")
    if cxx is None:
        raise RuntimeError("no C++ compiler (c++, g++ or clang++) on PATH")
    inc = os.path.join(prefix, "include")
    return [cxx, *FLAGS, *(f"-D{d}" for d in DEFINES), SOURCE, f"-I{inc}", f"-I{os.path.join(inc, 'eigen3')}",
            f"-L{os.path.join(prefix, 'lib')}", "-lpinocchio_default", "-lboost_serialization",
            f"-Wl,-rpath,{os.path.join(prefix, 'lib')}", "-o", out]


def library():
    """The compiled stepper (a ``ctypes.CDLL``), building it if needed; raises RuntimeError with
    the reason where it cannot be built."""
    if "lib" in _cached:
        return _cached["lib"]
    if "error" in _cached:
        raise RuntimeError(_cached["error"])
    try:
        prefix, version = _paths()
        if not os.path.exists(os.path.join(prefix, "include", "eigen3", "Eigen", "Core")):
            raise RuntimeError(f"no Eigen headers under {prefix}/include/eigen3 — pip install cmeel-eigen")
        with open(SOURCE, "rb") as f:
            key = hashlib.sha256(f.read() + repr((FLAGS, DEFINES, version, prefix)).encode()).hexdigest()[:16]
        cache = cache_dir()
        path = os.path.join(cache, f"pinocchio_stepper-{key}.so")
        # one lock per build: worker processes wait for one build of this library instead of racing,
        # and never for another venv's build of another one
        _remembered(path)  # a compile that failed before fails at once, without the lock (the compile holds it)
        with open(f"{path}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not os.path.exists(path):
                _remembered(path)  # another worker's compile failed while this one waited
                tmp = f"{path}.{os.getpid()}.tmp"
                proc = subprocess.run(_command(prefix, tmp), capture_output=True, text=True)
                if proc.returncode != 0:
                    error = _compile_error(proc.returncode, proc.stderr)
                    _remember(path, version, key, error)
                    raise RuntimeError(error)
                os.replace(tmp, path)
        lib = ctypes.CDLL(path)
    except Exception as e:  # noqa: BLE001 - every reason is reported, and the Python loop runs instead
        _cached["error"] = f"{type(e).__name__}: {e}" if not isinstance(e, RuntimeError) else str(e)
        raise RuntimeError(_cached["error"]) from None
    D, Li, In = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long), ctypes.POINTER(ctypes.c_int)
    forces = [ctypes.c_int, D, ctypes.c_int, In, D, D, In, ctypes.c_int, In, D, D]  # has_forces ... spring_params
    lib.dalembert_pin_fixed.restype = ctypes.c_int
    lib.dalembert_pin_fixed.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_int, D, D, ctypes.c_int, D, Li,
                                        *forces, D, D, Li, ctypes.c_char_p, ctypes.c_int]
    lib.dalembert_pin_acc.restype = ctypes.c_int
    lib.dalembert_pin_acc.argtypes = [ctypes.c_char_p, D, D, *forces, D, ctypes.c_char_p, ctypes.c_int]
    _cached["lib"] = lib
    return lib


def _compile_error(returncode, stderr):
    """Why a compile failed, in a few lines: the compiler's error lines (its warnings can fill the rest: Pinocchio
    4.0's headers warn at every deprecated container), else the end of what it wrote, and how it ended."""
    errors = [line.strip() for line in stderr.splitlines() if ": error:" in line or ": fatal error:" in line
              or "undefined reference" in line or line.startswith("collect2")]
    how = f"killed by signal {-returncode}" if returncode < 0 else f"exit status {returncode}"
    said = "\n".join(errors[:ERROR_LINES]) if errors else stderr.strip()[-1500:]
    return f"building {os.path.basename(SOURCE)} failed ({how}): {said}"


def _remember(path, version, key, error):
    """Write the marker of a failed compile of the library at ``path`` (atomically: a reader sees all or none)."""
    tmp = f"{path}{FAILED}.{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        json.dump({"pinocchio": version, "key": key, "source": os.path.basename(SOURCE), "error": error}, f)
    os.replace(tmp, path + FAILED)


def _remembered(path):
    """Raise RuntimeError with the remembered error where the compile of the library at ``path`` failed before."""
    if not os.path.exists(path + FAILED):
        return
    with open(path + FAILED) as f:
        failed = json.load(f)
    raise RuntimeError(f"{failed['source']} did not compile against Pinocchio {failed['pinocchio']} (remembered in "
                       f"{path + FAILED}: delete it to try again): {failed['error']}")


class NativeModel:
    """A ``PinocchioModel`` made ready for the compiled loop: the library loaded (built if
    needed), the model serialized and the constant loads and the springs packed, once (in the adapter's
    ``prepare``, not timed). ``RuntimeError`` with the reason where the library cannot be had.
    """

    def __init__(self, pm):
        self.lib = library()
        model = pm.model
        self.nq, self.nv = model.nq, model.nv
        self.model_bytes = model.saveToString().encode()
        self.dexpinv_kind = min(pm.dexpinv_kind(), 2)
        self.has_forces = int(pm.has_forces)
        self.springs = pm.springs
        self.const = np.zeros((model.njoints, 6))
        for jid, force in pm.const_f.items():
            self.const[jid] = force.vector
        world = pm.world_loads
        self.n_world = len(world)
        self.w_joint = _arr([w[0] for w in world] or [0], np.int32)
        self.w_point = _arr([w[1] for w in world] or [np.zeros(3)])
        self.w_vec = _arr([w[2] if w[2] is not None else w[3] for w in world] or [np.zeros(3)])
        self.w_torque = _arr([w[2] is None for w in world] or [0], np.int32)

    def _forces(self, elements):
        """The force arguments of both entry points, with the springs ``elements`` (``springs.pack``)."""
        D, In = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int)
        joints, points, params = (_arr(x, x.dtype) for x in springs.pack(elements))
        keep = (joints, points, params)  # alive until the call returns: the pointers point into them
        return keep, (self.has_forces, self.const.ctypes.data_as(D), self.n_world, self.w_joint.ctypes.data_as(In),
                      self.w_point.ctypes.data_as(D), self.w_vec.ctypes.data_as(D), self.w_torque.ctypes.data_as(In),
                      len(elements), joints.ctypes.data_as(In), points.ctypes.data_as(D), params.ctypes.data_as(D))

    def acceleration(self, q, v, elements=None):
        """One evaluation of the compiled right-hand side: the accelerations (nv,) at ``q (nq,)``, ``v (nv,)``,
        with the loads and the springs ``elements`` (default every one; the audit leaves one out)."""
        D = ctypes.POINTER(ctypes.c_double)
        q, v, a = _arr(q), _arr(v), np.full(self.nv, np.nan)
        keep, forces = self._forces(self.springs if elements is None else elements)
        err = ctypes.create_string_buffer(_ERR_LEN)
        if self.lib.dalembert_pin_acc(self.model_bytes, q.ctypes.data_as(D), v.ctypes.data_as(D), *forces,
                                      a.ctypes.data_as(D), err, _ERR_LEN):
            raise RuntimeError(f"the compiled right-hand side failed: {err.value.decode()}")
        return a

    def run(self, method, q0, v0, times, steps):
        """Step through ``times`` with ``steps[k]`` substeps per interval by ``method``.

        Returns ``(Q (n, nq), V (n, nv), steps taken, error message or None)``; rows after a
        non-finite state stay NaN, as in the Python loop.
        """
        D, Li, In = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long), ctypes.POINTER(ctypes.c_int)
        times, steps, q0, v0 = _arr(times), _arr(steps, np.int64), _arr(q0), _arr(v0)
        Q = np.full((len(times), self.nq), np.nan)
        V = np.full((len(times), self.nv), np.nan)
        taken, err = ctypes.c_long(0), ctypes.create_string_buffer(_ERR_LEN)
        keep, forces = self._forces(self.springs)
        rc = self.lib.dalembert_pin_fixed(
            self.model_bytes, METHODS[method], self.dexpinv_kind, q0.ctypes.data_as(D), v0.ctypes.data_as(D),
            len(times), times.ctypes.data_as(D), steps.ctypes.data_as(Li), *forces,
            Q.ctypes.data_as(D), V.ctypes.data_as(D), ctypes.byref(taken), err, _ERR_LEN)
        del keep
        return Q, V, int(taken.value), (err.value.decode() if rc else None)


def _arr(x, dtype=float):
    return np.ascontiguousarray(x, dtype=dtype)


if __name__ == "__main__":
    try:
        lib = library()
    except RuntimeError as e:
        print(f"pinocchio stepper: not built ({e}); the Pinocchio adapter will use its Python loop", file=sys.stderr)
        sys.exit(0)
    print(f"pinocchio stepper: {lib._name}")
