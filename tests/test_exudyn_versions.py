"""Exudyn across its versions: the shim for 1.11's API (``adapters/exudyn/compat.py``), the refusal it cannot
shim, and Exudyn 1.11.0 itself run in its engine environment.

The shim's 1.11 path is exercised here on the installed Exudyn (1.13.6 still takes 1.11's ``localPosition``
markers, ``rotationMarker0/1`` joint frames and ``radiusSphere``, deprecated): the system it builds must move as
the 1.13 path's does. Exudyn 1.11.0 itself runs only where its environment was made (``dalembert env create
exudyn==1.11.0``); without it that test skips, naming the command: no test here reaches the network.
"""

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter

exudyn = pytest.importorskip("exudyn")  # CI installs it: this never skips there

from dalembert.adapters.exudyn import compat  # noqa: E402  (imports exudyn's item classes when asked)

ADAPTER = get_adapter("exudyn")
OLD = "exudyn==1.11.0"
# The shim's 1.11 path against the 1.13 path on one Exudyn: the same system with a joint frame applied as
# R_marker @ rotationMarker (one extra rounding per product) instead of inside the marker, so the trajectories
# agree to rounding growing over the run. Measured: <= 3e-13 on these cases; a joint frame left out (the
# pendulum's axis turned) or a contact radius lost moves them by O(1).
SHIM_TOL = 1e-9
# Generalized-alpha's errors on Exudyn 1.11.0 against 1.13.6 (its environment's test), relative: measured at most
# 2.5e-6 here (the pendulum's reaction-force error, 1.1e-4 N, a difference of ~10 N forces), 5e-9 on its angles; a
# changed scheme or a lost joint frame moves them by O(1).
CROSS_VERSION_REL = 1e-4

CASES = [("pendulum", "generalized-alpha", {"joints": "redundant"}, {"t_final": 0.5}),
         ("heavy_top", "generalized-alpha", {"joints": "redundant", "node": "ep"}, {}),
         ("four_bar", "generalized-alpha", {"joints": "redundant"}, {"t_final": 0.2}),
         ("pivoted_rod", "rk44", {}, {"t_final": 0.5}),
         ("ball_slide_to_roll", "generalized-alpha", {}, {"t_final": 0.3})]


def _run(case, settings):
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    return prepared, ADAPTER.run(prepared).trajectory


def _legacy(monkeypatch):
    """Make the adapter build as it does on Exudyn 1.11: markers without frames, 1.11's contact radius."""
    monkeypatch.setattr(compat, "framed_markers", lambda: False)
    monkeypatch.setattr(compat, "sphere_radius_field", lambda: compat.SPHERE_RADIUS[1])
    from dalembert.adapters.exudyn import contact

    monkeypatch.setattr(contact, "sphere_radius_field", lambda: compat.SPHERE_RADIUS[1])


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # 1.13 on 1.11's parameters, the point of the test
@pytest.mark.parametrize("name,integrator,options,params", CASES, ids=[c[0] for c in CASES])
def test_the_shims_old_api_path_moves_as_the_new_one(monkeypatch, name, integrator, options, params):
    """Each case built the 1.11 way (frames in the joints, not the markers) runs as built the 1.13 way, and its
    joints read back alike (``joint_readout``: kind, axis, joint point, initial coordinate)."""
    case = make_case(name, **params)
    settings = Settings(integrator, dt=1e-3, options=options)
    new_p, new = _run(case, settings)
    _legacy(monkeypatch)
    old_p, old = _run(case, settings)
    mbs = old_p.system.mbs
    joints = [mbs.GetObject(i) for i in range(mbs.systemData.NumberOfObjects())
              if mbs.GetObject(i)["objectType"] == "JointGeneric"]
    if name == "pendulum":  # the joint's frame is in the joint now, not its markers (the axis is not z)
        assert not np.array_equal(joints[0]["rotationMarker0"], np.eye(3))
        assert np.array_equal(mbs.GetMarker(int(joints[0]["markerNumbers"][0]))["localHT"][:3, :3], np.eye(3))
    for body in new.bodies:
        for field in ("position", "quaternion", "velocity", "angular_velocity"):
            a, b = getattr(new.bodies[body], field), getattr(old.bodies[body], field)
            assert np.abs(a - b).max() < SHIM_TOL, (body, field, np.abs(a - b).max())
    assert set(new.extras) == set(old.extras)
    for key in new.extras:
        assert np.abs(new.extras[key] - old.extras[key]).max() < SHIM_TOL * max(1.0, np.abs(new.extras[key]).max())
    for child, got in new_p.system.joint_readout.items():
        back = old_p.system.joint_readout[child]
        assert back["kind"] == got["kind"]
        for key in ("axis", "parent_point", "q0", "v0"):
            if got.get(key) is not None:
                assert np.allclose(back[key], got[key], atol=SHIM_TOL), (child, key)


def test_the_installed_exudyn_takes_the_new_api():
    """On the installed Exudyn (1.13) the shim makes the calls the adapter made before it: frames in markers."""
    assert compat.framed_markers() and compat.sphere_radius_field() == compat.SPHERE_RADIUS[0]
    s = exudyn.SimulationSettings()
    compat.set_solver(s, exudyn.DynamicSolverType.RK44)
    assert s.timeIntegration.solverType == exudyn.DynamicSolverType.RK44 == compat.solver_of(s)


def test_a_ball_joint_with_trapezoidal_index2_is_refused_before_1_13(monkeypatch):
    """Exudyn 1.11.0's TrapezoidalIndex2 stalls on heavy_top's ball joint after its process's first solve: refused
    there with the reason and the way out, run at 1.13, and generalized-alpha runs at either."""
    scene = make_case("heavy_top").scene
    trapezoidal = Settings("trapezoidal-index2", dt=5e-3, options={"joints": "redundant"})
    monkeypatch.setattr(type(ADAPTER), "version", lambda self: "1.11.0")
    why = ADAPTER.unsupported(scene, trapezoidal)
    assert "exudyn 1.11.0: trapezoidal-index2 on a ball joint" in why and "use generalized-alpha" in why
    assert ADAPTER.unsupported(scene, Settings("generalized-alpha", dt=5e-3, options={"joints": "redundant"})) is None
    assert ADAPTER.unsupported(make_case("pendulum").scene, trapezoidal) is None  # no ball joint
    monkeypatch.setattr(type(ADAPTER), "version", lambda self: "1.13.6")
    assert ADAPTER.unsupported(scene, trapezoidal) is None


def test_versions_before_1_11_are_refused_naming_what_was_measured():
    assert ADAPTER.version_problem("1.11.0") is None and ADAPTER.version_problem("1.13.6") is None
    why = ADAPTER.version_problem("1.9.0")
    assert "exudyn 1.9.0 is outside the versions its adapter supports, >=1.11" in why and "1.11.0 and 1.13.6" in why
    assert "ObjectContactSphereSphere" in why


@pytest.mark.long
def test_exudyn_1_11_runs_in_its_environment_as_1_13_does(tmp_path):
    """Exudyn 1.11.0 in its environment: jointed (redundant, minimal) and free cases run, recorded as 1.11.0, with
    generalized-alpha's errors those of 1.13.6 (``CROSS_VERSION_REL``)."""
    from dalembert.harness.cli import main
    from dalembert.environments import environment
    from dalembert.store import Store

    if not environment(OLD).exists:
        pytest.skip(f"no {OLD} environment here: make it with dalembert env create {OLD} (reaches the package index)")
    out = tmp_path / "r"
    code = main(["run", "--engine", OLD, "--engine", "exudyn", "--case", "pendulum", "--case", "free_top",
                 "--integrator", "generalized-alpha", "--integrator", "rk44", "--dt", "5e-3", "--param",
                 "t_final=0.5", "--quick", "--jobs", "1", "--no-maps", "--out", str(out)])
    assert code == 0
    records = Store(out).records()
    old = [r for r in records if r.engine == OLD]
    assert old and {r.engine_version for r in old} == {"1.11.0"}
    assert all(r.status == "ok" for r in records), [(r.key, r.message) for r in records if r.status != "ok"]
    new = {(r.case, r.settings.integrator, tuple(sorted(r.settings.options.items()))): r
           for r in records if r.engine == "exudyn"}
    for r in old:
        twin = new[(r.case, r.settings.integrator, tuple(sorted(r.settings.options.items())))]
        if r.settings.integrator == "generalized-alpha":
            for quantity, (value, _) in r.errors.items():
                assert value == pytest.approx(twin.errors[quantity][0], rel=CROSS_VERSION_REL), (r.key, quantity)
