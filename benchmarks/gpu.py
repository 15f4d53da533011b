"""The float32 engines on a GPU, where there is one: MuJoCo Warp's and MJX's parity with MuJoCo C, and a batched
stability map, each beside the same on the CPU. Safe to run blindly: without a GPU it says so in one line, exits 0.

    python -m benchmarks.gpu            # a few minutes on a GPU (most of it the engines' first compilations)

1. Parity (``adapters.mujoco_warp.parity``, ``adapters.mjx.parity``), MuJoCo Warp with ``device=cuda`` and MJX
   with ``device=gpu`` (float32), on four canonical cases (``CASES``) at RK4, dt = 1e-3: 100 steps' largest
   ``qpos``/``qvel`` difference from MuJoCo C (same compiled model), and the largest attitude (rad) and position
   (m) differences over the first ``SECONDS`` of the case beside the torque-free top's float32 floor (RK4 in
   float32 against itself in double). A GPU's kernels round as the CPU's in float32 but may sum in another
   order, so a difference at the floor is the number type's; one far above it a different computation.
2. Map: ``dalembert run --case free_top_fast_spin --param spin=log:5,500,16 --param t_final=1 --engine
   mujoco_warp --integrator rk4 --search dt --dt 1e-3,1e-1 --batch`` (sampled every 0.1 s) with ``--option
   device=cuda`` and on the CPU: each map's wall time and runs, and each spin's stable step (the largest stable
   probe) on both; the same number type on both, so the boundaries should agree to the search's resolution.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

SECONDS = 1.0  # of each canonical case: the parity's horizon (the float32 floor grows with it)
DT = 1e-3
ONE_STEP_N = 100  # steps of the one-step parity: MuJoCo Warp's own checks compare one to a few steps
# Of the canonical cases: a joint, the torque-free top (with its float32 floor), a top under gravity and a chain of
# joints, each a model the engines compile afresh on a GPU (MJX: ~10-60 s a model), so the script fits ~5 minutes.
CASES = ("pendulum", "free_top", "heavy_top", "chain")
# the probes' steps must divide the sample interval: 0.1 s, as ``benchmarks.map``'s map
MAP = ["--case", "free_top_fast_spin", "--param", "spin=log:5,500,16", "--param", "t_final=1", "--param",
       "sample_interval=0.1", "--integrator", "rk4", "--search", "dt", "--dt", "1e-3,1e-1", "--batch"]


def devices():
    """``{engine: device}`` of the float32 engines whose GPU this machine has (Warp's ``cuda``, JAX's ``gpu``), and
    ``{engine: why not}`` of the others (the option's refusal, or the engine missing)."""
    found, missing = {}, {}
    for engine, name, module in (("mujoco_warp", "cuda", "dalembert.adapters.warp_runtime"),
                                 ("mjx", "gpu", "dalembert.adapters.mjx.stepping")):
        try:
            problem = __import__(module, fromlist=["device_problem"]).device_problem(name)
        except ImportError as e:
            problem = f"{engine} not installed ({e})"
        (missing if problem else found)[engine] = problem or name
    return found, missing


def parity(engine, device):
    from dalembert import Settings, make_case
    from dalembert.adapters import get_adapter
    one_step, horizon = _parity(engine)
    print(f"\n{engine} {get_adapter(engine).version()} on {device} (float32) vs MuJoCo C "
          f"{get_adapter('mujoco').version()}, RK4, dt = {DT:g}, first {SECONDS:g} s")
    print(f"{'case':<24}{'100-step qpos':>14}{'qvel':>10}{'attitude':>10}{'position':>10}{'f32 floor':>10}"
          f"{'wall s':>8}")
    for name in CASES:
        case = make_case(name, t_final=SECONDS)
        s = Settings("rk4", dt=DT, options={"device": device})
        t0 = time.perf_counter()
        one = one_step(case, s, n_steps=ONE_STEP_N)
        h = horizon(case, s)
        print(f"{name:<24}{one['qpos']:>14.1e}{one['qvel']:>10.1e}{h['orientation']:>10.1e}{h['position']:>10.1e}"
              f"{h['float32_floor']:>10.1e}{time.perf_counter() - t0:>8.1f}", flush=True)


def _parity(engine):
    if engine == "mjx":
        from dalembert.adapters.mjx.parity import horizon, one_step
    else:
        from dalembert.adapters.mujoco_warp.parity import horizon, one_step
    return one_step, horizon


def stability_map(device):
    """The batched map of MuJoCo Warp on ``device`` and on the CPU: wall time, runs and each spin's stable step."""
    from dalembert.boundary import boundaries
    from dalembert.store import Store

    print(f"\nstability map, MuJoCo Warp RK4 batched: {' '.join(MAP)}")
    stable = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, on in enumerate((device, "cpu")):
            out = os.path.join(tmp, f"map{k}")
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", *MAP, "--engine",
                                   "mujoco_warp", "--option", f"device={on}", "--out", out],
                                  capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if proc.returncode != 0:
                print(f"{on}: dalembert run failed (exit {proc.returncode}): {proc.stderr[-1500:]}")
                continue
            records = [r for r in Store(out).records() if r.engine == "mujoco_warp"]
            devices = sorted({r.cost.device for r in records if r.status != "unsupported"})
            stable[k] = {float(b.params["spin"]): b.stable.passed for b in boundaries(records)}
            print(f"{on}: {len(records)} runs in {wall:.1f} s (records' device: {', '.join(devices)})", flush=True)
    if len(stable) == 2:
        print(f"{'spin rad/s':>11}{'stable dt ' + device:>22}{'stable dt cpu':>16}")
        for spin in sorted(stable[1]):
            g, c = stable[0].get(spin), stable[1][spin]
            print(f"{spin:>11.3g}{_dt(g):>22}{_dt(c):>16}")


def _dt(dt):
    return "none" if dt is None else f"{dt:.3g}"


def main():
    found, missing = devices()
    if not found:
        print(f"benchmarks.gpu: no GPU here ({'; '.join(f'{e}: {why}' for e, why in missing.items())}) — nothing "
              "run; run it on a machine with a CUDA GPU")
        return 0
    for engine, why in missing.items():
        print(f"{engine}: skipped ({why})")
    np.set_printoptions(precision=3)
    for engine, device in found.items():
        parity(engine, device)
    if "mujoco_warp" in found:
        stability_map(found["mujoco_warp"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
