"""Option ``device`` of the float32 engines (MJX: JAX's ``cpu`` | ``gpu``; MuJoCo Warp and Newton: Warp's ``cpu`` |
``cuda`` | ``cuda:N``): declared with the CPU as default, a device this machine lacks refused with the reason
naming the option (a run's ``unsupported``, never the harness's main process's, which must not import JAX or
Warp), and the device a default run stepped on in its record.

What runs on a GPU is ``benchmarks/gpu.py``'s (it says so and exits where there is none); here the CPU only.
"""

import json
import subprocess
import sys
from importlib.util import find_spec

import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.harness.execute import QUICK, execute
from dalembert.harness.matrix import expand

# engine -> (the GPU device its option names, an integrator it has)
ENGINES = {"mjx": ("gpu", "euler"), "mujoco_warp": ("cuda", "euler"), "newton": ("cuda", "featherstone")}
SHORT = {"t_final": 0.05}  # 5 samples of the pendulum: the record, not the physics, is under test


def _installed(engine):
    return all(find_spec(m) is not None for m in {"mjx": ("jax",), "mujoco_warp": ("warp", "mujoco_warp"),
                                                   "newton": ("warp", "newton")}[engine])


def _has_gpu(engine):
    """Whether this machine has the device the engine's option names (then the refusal is not asserted)."""
    if engine == "mjx":
        import jax

        try:
            return bool(jax.devices("gpu"))
        except RuntimeError:
            return False
    from dalembert.adapters.warp_runtime import init

    wp, _ = init()
    return wp.is_cuda_available() and wp.get_cuda_device_count() > 0


def _engine(engine):
    """The engine's parameter, skipped where the engine is not installed (MJX is in dalembert[all])."""
    return pytest.param(engine, marks=pytest.mark.skipif(not _installed(engine), reason=f"{engine} not installed"))


@pytest.mark.parametrize("engine", list(ENGINES))
def test_the_option_is_declared_with_the_cpu_as_default(engine):
    option = get_adapter(engine).options["device"]
    assert option.default == "cpu" and ENGINES[engine][0] in option.choices
    integrator = ENGINES[engine][1]
    assert "device" in get_adapter(engine).integrators[integrator].options  # every integrator takes it
    assert option.problem("device", "tpu", integrator).startswith("options.device: unknown 'tpu'")


@pytest.mark.parametrize("engine", [_engine(e) for e in ENGINES])
def test_a_device_this_machine_lacks_is_refused_naming_the_option(engine):
    name, integrator = ENGINES[engine]
    if _has_gpu(engine):
        pytest.skip(f"this machine has a {name}: benchmarks/gpu.py runs on it")
    adapter, scene = get_adapter(engine), make_case("pendulum", **SHORT).scene
    settings = Settings(integrator, dt=1e-2, options={"device": name})
    reason = adapter.unsupported(scene, settings)
    assert reason is not None and reason.startswith("options.device: no ") and "run with device=cpu" in reason, reason
    assert adapter.unsupported(scene, Settings(integrator, dt=1e-2)) is None  # the CPU is always there


@pytest.mark.parametrize("engine", [_engine(e) for e in ENGINES])
def test_the_main_process_asks_without_importing_jax_or_warp(engine):
    """``unsupported_before_build`` (what ``dalembert run`` asks before forking its workers) passes a GPU device
    on, for the run to refuse, and imports neither JAX nor Warp (a process that started JAX's threads must not
    fork)."""
    name, integrator = ENGINES[engine]
    code = ("import json, sys; from dalembert import Settings, make_case; from dalembert.adapters import get_adapter;"
            f"a = get_adapter({engine!r}); s = make_case('pendulum').scene;"
            f"r = a.unsupported_before_build(s, Settings({integrator!r}, dt=1e-2, options={{'device': {name!r}}}));"
            "print(json.dumps([r, sorted(m for m in ('jax', 'warp') if m in sys.modules)]))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [None, []], out.stdout


@pytest.mark.long  # compiles (or loads from the caches) each engine's step
@pytest.mark.parametrize("engine", [_engine(e) for e in ENGINES])
def test_a_default_run_records_the_cpu(engine):
    specs, _ = expand(cases=["pendulum"], engines=[engine], integrators=[ENGINES[engine][1]], dts=[1e-2],
                      params=SHORT)
    record, _ = execute(specs[0], QUICK)
    assert record.status == "ok", record.message
    assert record.cost.device == "cpu"


@pytest.mark.long
@pytest.mark.parametrize("engine", [_engine(e) for e in ("mjx", "mujoco_warp")])
def test_a_run_that_diverges_records_its_device_too(engine):
    """The top spun at 500 rad/s blows up at dt 0.1 s (RK4; non-finite by t = 0.3 s in float32)."""
    specs, _ = expand(cases=["free_top_fast_spin"], engines=[engine], integrators=["rk4"], dts=[0.1],
                      params={"spin": 500.0, "t_final": 1.0, "sample_interval": 0.1})
    record, _ = execute(specs[0], QUICK)
    assert record.status == "diverged", record.message
    assert record.cost.device == "cpu"
