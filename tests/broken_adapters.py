"""Deliberately misbehaving adapters for the run-matrix tests (importable by worker processes)."""

import time
from dataclasses import replace

import numpy as np

from dalembert.adapters import Adapter, IntegratorSpec
from dalembert.adapters.reference import ReferenceAdapter


class Broken(ReferenceAdapter):
    """Reference physics, but each integrator misbehaves in its own way."""

    integrators = {"raises": IntegratorSpec(True), "nan": IntegratorSpec(True), "hangs": IntegratorSpec(True),
                   "rk4": IntegratorSpec(True)}

    def check(self, scene, times, settings):
        Adapter.check(self, scene, times, settings)

    def prepare(self, scene, times, settings):
        from dalembert.settings import Settings

        return super().prepare(scene, times, Settings("rk4", dt=settings.dt)), settings.integrator

    def run(self, prepared):
        inner, mode = prepared
        if mode == "raises":
            raise RuntimeError("engine exploded on purpose")
        if mode == "hangs":
            time.sleep(3600)
        out = super().run(inner)
        if mode == "nan":
            b = next(iter(out.trajectory.bodies.values()))
            b.position[len(b.position) // 2:] = np.nan
        return out

    def audit(self, prepared, outcome):
        return super().audit(prepared[0], outcome)


class NoFollower(ReferenceAdapter):
    """The reference without follower forces: scenes with them are unsupported."""

    effects = ReferenceAdapter.effects - {"load:follower_force"}


class Still(ReferenceAdapter):
    """The reference physics without the scene's loads: a driven body never moves (an engine
    that silently left out what drives the motion)."""

    def prepare(self, scene, times, settings):
        return super().prepare(replace(scene, loads=()), times, settings)


class Threads(ReferenceAdapter):
    """The reference, whose audit also reports the threads of the process's BLAS pools."""

    def audit(self, prepared, outcome):
        from threadpoolctl import threadpool_info

        # (a BLAS built without threads has one whatever it is asked: OpenSim's OpenBLAS 0.3.15, threading layer
        # "disabled", loaded in a worker once Simbody is installed)
        blas = [p["num_threads"] for p in threadpool_info()
                if p["user_api"] == "blas" and p.get("threading_layer") != "disabled"]
        return {**super().audit(prepared, outcome), "blas_threads": blas}


class SlowReadBack(ReferenceAdapter):
    """The reference, whose read-back takes ``PAUSE_S`` longer."""

    PAUSE_S = 0.5

    def run(self, prepared):
        out = super().run(prepared)
        read_back = out.read_back

        def slow():
            time.sleep(self.PAUSE_S)
            return read_back()

        return replace(out, read_back=slow)


class Loaded(ReferenceAdapter):
    """The reference, whose audit says whether this process loaded it (``Adapter.load``) before its first run."""

    loaded = 0  # loads in this process
    runs = 0  # runs started in this process

    def load(self):
        super().load()
        Loaded.loaded += 1 if Loaded.runs == 0 else 0

    def run(self, prepared):
        Loaded.runs += 1
        return super().run(prepared)

    def audit(self, prepared, outcome):
        return {**super().audit(prepared, outcome), "loaded_before_first_run": Loaded.loaded}


class Unloadable(ReferenceAdapter):
    """The reference, whose ``load`` raises: its runs go on (the error, where real, shows in each run)."""

    def load(self):
        raise ImportError("no module named 'unloadable_engine' (on purpose)")


def _mujoco():
    from dalembert.adapters.mujoco import MujocoAdapter

    return MujocoAdapter


class ForceBlind(_mujoco()):
    """MuJoCo, but its trajectories carry no contact force: an engine that does not report one (the quantities made
    from it are then not measured)."""

    def run(self, prepared):
        from dalembert.contact import FORCE_PREFIX

        out = super().run(prepared)
        extras = out.trajectory.extras  # (read back once, and kept: Outcome.trajectory is cached)
        for key in [k for k in extras if k.startswith(FORCE_PREFIX)]:
            del extras[key]
        return out
