"""Hard cases: the reference's own verdict, every engine's verdict, and exactness near the separatrix."""

import numpy as np
import pytest

from dalembert import Settings, make_case, spatial
from dalembert.case import load_cases
from dalembert.errors import QUANTITIES, trajectory_errors
from dalembert.harness.matrix import expand, split
from dalembert.judge import VERDICTS, judge
from dalembert.store import Store
from dalembert.reference import simulate
from dalembert.reference.closed_form import TorqueFreeTop
from taylor import integrate_top
from truths import contract_case, shared_truth_from

HARD = [n for n, f in load_cases().items() if "hard" in f.tags]
# The built-in engines (other tests register deliberately broken ones in this process).
ENGINES = ["reference", "mujoco", "pinocchio", "exudyn"]
# Each engine's fourth-order fixed-step integrator: the smoke test of the stability grid.
SMOKE_INTEGRATORS = ["rk4", "rk44"]
# The smoke matrix's horizon, s: 50 steps at its dt of 1e-2. Its 49 runs get the verdicts they get over 1 s
# (measured at both: 34 stable, 9 drifts, 6 diverged; the stiff flyball_governor's non-finite from 0.03 s); most
# of the matrix's CPU is the truths of the cases without a closed form (flyball_governor's Radau, robot_free_fall's
# 17 bodies), which grow with it (measured: 8.8 s over 1 s, 6.2 s over 0.5 s).
SMOKE_HORIZON = 0.5
# Per-run limit of the smoke matrix, s: it catches a hung run, not a slow one. Each smoke run takes seconds
# on an idle machine; 30 min is beyond any loaded machine's slowdown of that and inside CI's 90-min limit
# (120 s was a false alarm: one run timed out while the machine's 2 cores ran 4 other jobs).
HUNG_RUN_S = 1800
# Horizons for the tests (the full ones are for `dalembert run --tag hard`).
SHORT = {"free_top_long_horizon": dict(t_final=5.0), "pivoted_rod_violent": {},
         "robot_free_fall": {},  # its own 1 s (the case contract's too: one truth), not 2 s of a 17-body Kane loop
         "particle_box_welded": dict(t_final=0.5),  # 27 bodies: the reference's Kane loop is slow
         "flyball_governor": dict(t_final=0.5)}  # its small steps (STEP) make each second 10000 evaluations
# The reference's step in the test below, where 1e-3 is beyond a case's stability: flyball_governor is stiff (its
# equations decay at 8117 1/s: RK4's stability bound is 2.8 / 8117 = 3.4e-4 s).
STEP = {"flyball_governor": 2e-4}


def test_the_hard_cases_are_registered():
    assert set(HARD) >= {"free_top_fast_spin", "free_top_long_horizon", "free_top_near_symmetric",
                         "free_top_slender", "free_top_separatrix", "pivoted_rod_violent", "particle_box_welded",
                         "chain_chaotic", "kovalevskaya_top", "flyball_governor"}


def test_welds_hold_in_exudyn_redundant_coordinates():
    """The 27 welded particles as rigid bodies + 26 generic joints: the box stays rigid and
    follows the rigid-body closed form (second order)."""
    from dalembert.adapters import get_adapter
    from dalembert import invariants

    case = make_case("particle_box_welded", t_final=0.5)
    exudyn = get_adapter("exudyn")
    s = Settings("generalized-alpha", dt=1e-3, options={"joints": "redundant"})
    traj = exudyn.run(exudyn.prepare(case.scene, case.times, s)).trajectory
    errors = trajectory_errors(traj, case.exact(case.times))
    assert errors["orientation"][0] < case.tolerances["orientation"].value
    assert errors["position"][0] < case.tolerances["position"].value
    assert invariants.drift("pairwise_distance", case.scene, traj) < case.tolerances["pairwise_distance"].value


def test_separatrix_closed_form_is_still_exact():
    """2 E I2 / |L|^2 = 1 - 1e-9: against the 40-digit Taylor integration, 1e-11 rad over 20 s."""
    case = make_case("free_top_separatrix")
    w0 = case.scene.joints[0].v0[3:]
    t = np.linspace(0.0, 20.0, 11)
    q_ref, _ = integrate_top((1.0, 2.0, 3.0), w0, spatial.IDENTITY_QUAT, t)
    top = TorqueFreeTop(np.diag([1.0, 2.0, 3.0]), np.array(w0))
    # 1 - k^2 = (I3 - I1)(M^2 - 2E I2) / ((I3 - I2)(M^2 - 2E I1)) (Landau & Lifshitz, section 37)
    # with M^2 - 2E I2 = gap M^2 and, for w0 ~ (0, spin, 0), M^2 - 2E I1 ~ M^2 (I2 - I1) / I2:
    # (2 / 1) gap (2 / 1) = 4 gap; the off-axis components change it by O(gap) relative.
    assert top.m1 == pytest.approx(4e-9, rel=1e-6)
    assert np.max(spatial.rotation_angle(top.quaternion(t), q_ref)) < 1e-11


@pytest.mark.parametrize("name", HARD)
def test_reference_is_stable_and_matches_the_truth(name, shared_dir):
    """The reference's rkmk4 against the closed form, or, for a case without one, against its truth (the
    reference's DOP853 or, for a stiff case, Radau at 1e-12: another integrator), computed once in the session
    (``truths.shared_truth``: the case contract needs the same truth where the horizons agree; where this one is
    shorter, its samples are the first of the contract's: ``truths.shared_truth_from``)."""
    case = make_case(name, **SHORT.get(name, dict(t_final=2.0)))
    traj = simulate(case.scene, case.times, Settings("rkmk4", dt=STEP.get(name, 1e-3)))[0]
    from dalembert import invariants

    errors = trajectory_errors(traj, shared_truth_from(case, contract_case(name), shared_dir))
    drifts = invariants.summary(case.scene, traj, case.conserved, case.invariants).drifts
    judged = judge("ok", "", {q: mx for q, (mx, _) in errors.items()}, drifts, case.tolerances)
    assert judged.verdict == "stable", judged.reason
    assert judged.within_tolerance, judged.beyond
    for q, tol in case.tolerances.items():
        if q in QUANTITIES and q in errors:
            assert errors[q][0] <= tol.value, (q, errors[q][0])


@pytest.mark.long
def test_every_engine_gets_a_verdict_on_every_hard_case(tmp_path):
    """A smoke test of the stability grid: every hard case in every built-in engine, with its
    fourth-order fixed-step integrator at a coarse step over ``SMOKE_HORIZON``, gets a stored verdict and no
    crash — through the command line in a fresh process, as a user runs it. (The full grid,
    every integrator at dt 1e-2 and 1e-3 over the full horizons, is ``dalembert run --tag hard``.)"""
    import subprocess
    import sys

    out = tmp_path / "hard"
    selection = ["--tag", "hard", *[a for e in ENGINES for a in ("--engine", e)],
                 *[a for i in SMOKE_INTEGRATORS for a in ("--integrator", i)], "--dt", "1e-2",
                 "--param", f"t_final={SMOKE_HORIZON}", "--no-maps", "--quick"]
    # no deadline of its own: a busy CI machine makes this slow, not wrong
    proc = subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", *selection,
                           "--timeout", str(HUNG_RUN_S),
                           "--out", str(out)], capture_output=True, text=True)
    assert "runs stored" in proc.stderr, proc.stderr[-2000:]
    records = Store(out).records()
    specs, _ = expand(tags=["hard"], engines=ENGINES, integrators=SMOKE_INTEGRATORS, dts=[1e-2],
                      params={"t_final": SMOKE_HORIZON})
    runnable, _ = split(specs)  # (what an engine refuses before the build is listed in the manifest, not run)
    assert len(records) == len(runnable)
    assert {(r.case, r.engine) for r in records} == {(s.case, s.engine) for s in runnable}
    # every hard case runs in some engine, and every engine runs some hard case
    assert {r.case for r in records} == set(HARD) and {r.engine for r in records} == set(ENGINES)
    verdicts = {}
    for r in records:
        verdict = r.judgement.verdict
        assert verdict in VERDICTS and verdict != "timeout", (r.case, r.engine, r.settings_label, verdict)
        verdicts[verdict] = verdicts.get(verdict, 0) + 1
    assert verdicts.get("stable", 0) > 0
