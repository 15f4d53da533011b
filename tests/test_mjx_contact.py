"""MJX runs the contact cases with MuJoCo's mapping (the same MJCF: geoms, planes, explicit pairs, friction,
restitution as solref's damping ratio), its contact options reach the device, and what MJX lacks is refused with the
reason: noslip (MJX's JAX implementation has no noslip pass) and a frictionless pair under the elliptic cone
(``mjx.make_data``).
MJX 3.17 on JAX's CPU backend, semi-implicit Euler at dt = 1e-3 (the numbers each bound rests on are in its
comment; MuJoCo C 4.0 gives the same figures at these settings)."""

import pytest
from installed import needs

pytestmark = needs("mujoco.mjx", "jax")

from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.kinds import CONTACT_EFFECTS  # noqa: E402
from dalembert.settings import Settings  # noqa: E402
from engine_runs import run_case  # noqa: E402

ADAPTER = get_adapter("mjx")
DT = 1e-3
# MJX's default (pyramidal cone, impratio 1) lets the box that must stick creep at a measured 1.79 mm/s over the
# default block_on_incline (float32; 1.80 mm/s in float64), MuJoCo C's 1.8 mm/s; the bound leaves ~1.7x.
DEFAULT_CREEP_BOUND = 3e-3
# The elliptic cone with impratio 10 cuts it tenfold: measured 1.01e-4 m/s in float32 (float64: 9.04e-5 m/s, MuJoCo
# C's figure at these settings); the bound leaves 3x and sits below the default's creep, so options that never
# reach the device fail it.
ELLIPTIC_IMPRATIO_CREEP_BOUND = 3e-4
# MJX starts the ball rolling 6.4 ms after the closed form's onset (float32; 6.6 ms in float64; MuJoCo's soft
# friction: the 0.313-0.319 s for t* = 0.2912 s); the bound leaves ~1.5x.
ROLL_ONSET_BOUND = 1e-2
# Restitution 0.5 mapped to solref's damping ratio: the first two apexes miss e^2 h and e^4 h by at most a measured
# 0.0758 m of the 1-m drop (the mapping ignores MuJoCo's impedance and gravity during the contact); leaves ~1.3x.
APEX_ERROR_BOUND = 0.1
# The spheres' velocities after the impact miss the closed form's by a measured 0.0164 m/s in float64 (0.0442 in
# float32) at the 1-m/s approach; the float64 bound leaves ~1.8x.
AFTER_BOUND = 3e-2


def run(name, options=None, **params):
    return run_case("mjx", name, Settings("euler", dt=DT, options=options or {}), **params)[1:]


def test_mjx_declares_contact_and_mujocos_contact_options():
    assert CONTACT_EFFECTS <= ADAPTER.effects
    assert {"cone", "impratio", "noslip_iterations", "contact_timeconst"} <= set(ADAPTER.options)
    assert all("cone" in spec.options for spec in ADAPTER.integrators.values())


@pytest.mark.long  # each run compiles MJX's rollout and its contact forces (~5-9 s each on 2 cores)
def test_block_that_must_stick_creeps_as_mujoco_and_the_options_reach_the_device():
    _, _, default = run("block_on_incline")
    prepared, outcome, elliptic = run("block_on_incline", {"cone": "elliptic", "impratio": 10.0})
    assert elliptic["creep"] < ELLIPTIC_IMPRATIO_CREEP_BOUND < default["creep"] < DEFAULT_CREEP_BOUND
    outcome.trajectory  # (the read-back fills the audit's figures)
    audit = ADAPTER.audit(prepared, outcome)
    assert (audit["cone"], audit["cone_device"], audit["impratio"], audit["impratio_device"]) == (
        "elliptic", "elliptic", 10.0, 10.0)
    assert "noslip" in audit["noslip"] and audit["contact_pairs"] and audit["default_collisions"] == 0
    # the read-backs' contact-force programs (one per model) are kept in this process, as the rollouts are: a later
    # run of either block (test_contact_forces' default one) compiles no forces again (5-9 s each on 2 cores)
    from dalembert.adapters.mjx import contact

    assert contact._forward_contacts()._cache_size() >= 2


@pytest.mark.long
def test_ball_starts_rolling_near_t_star():
    *_, drifts = run("ball_slide_to_roll")
    assert 0.0 < drifts["roll_onset_error"] < ROLL_ONSET_BOUND


# float64 last (a process switching precision clears JAX's caches: ``adapters.mjx.stepping``): the MJX tests before
# this file's in collection order (test_mjx's) end in float32, those after (test_mujoco_*'s) are in float64
@pytest.mark.long
def test_bouncing_ball_apexes_and_sphere_collision_in_float64():
    *_, ball = run("bouncing_ball", {"precision": "float64"})
    assert ball["apex_error"] < APEX_ERROR_BOUND
    *_, spheres = run("sphere_collision", {"precision": "float64"})
    assert spheres["velocity_after_error"] < AFTER_BOUND
    assert spheres["linear_momentum"] < 1e-12  # (float64: equal and opposite contact forces, to roundoff)


def test_what_mjx_lacks_is_refused_with_the_reason():
    block, ball = make_case("block_on_incline"), make_case("bouncing_ball")
    reason = ADAPTER.unsupported(block.scene, Settings("euler", dt=DT, options={"noslip_iterations": 10}))
    assert reason.startswith("options.noslip_iterations: MJX's JAX implementation has no noslip pass")
    assert "--engine mujoco" in reason
    # a frictionless pair (condim 1) under the elliptic cone: MJX's own refusal, from mjx.make_data
    reason = ADAPTER.unsupported(ball.scene, Settings("euler", dt=DT, options={"cone": "elliptic"}))
    assert reason.startswith("MJX cannot put this model on the device (mjx.make_data") and "condim=1" in reason
    # the same cone with friction runs, and noslip at its default is no refusal
    assert ADAPTER.unsupported(block.scene, Settings("euler", dt=DT, options={"cone": "elliptic"})) is None
    assert ADAPTER.unsupported(block.scene, Settings("euler", dt=DT, options={"noslip_iterations": 0})) is None
