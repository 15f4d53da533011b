"""The reference solver: orders of convergence, agreement of formulations, settings checks."""

import numpy as np
import pytest

from dalembert import Settings, make_case, spatial
from dalembert.errors import trajectory_errors
from dalembert.invariants import orthonormality_error
from dalembert.reference import simulate
from dalembert.reference.integrators import INTEGRATORS
from dalembert.reference.solver import FORMULATIONS
from dalembert.reference.newton_euler import NewtonEuler
from dalembert.scene import Body, Joint, Scene, Spring
from scenes import chain_case, free_body_world_loads_case

ORDER_SLACK = 0.3  # measured orders within this of the theory (asymptotic regime, 2 step sizes)
FORMULATION_AGREEMENT = 1e-12  # rad or m over 2 s: same method, different algebra -> roundoff only
# Central differences of a linear right-hand side are exact but for roundoff over the 1e-6 step (measured 1.4e-10
# and 2.1e-12 relative).
DECAY_RATE_RTOL = 1e-7
# Radau at 1e-12 on the damped oscillators over 2 s: measured 4.5e-13 and 5.2e-13 m of a 0.3-m stretch.
RADAU_TOL = 1e-11

FREE_CASES = ["free_top", "free_top_intermediate", "particle_box"]
# Kane's read-back at every sample at once against one state at a time: the same terms, summed by numpy's
# stacked products, solves and SVDs instead of its single ones; measured up to 6.7e-15 of each quantity's
# largest value (heavy_top's reactions) over the scenes below -> roundoff, with a margin.
STACKED_AGREEMENT = 1e-13
# Off the loops' manifolds by this (rad or m, a dense output's error at a loose tolerance), so that the
# read-back's projection iterates (``reference.loops.ClosedLoops.project``).
OFF_MANIFOLD = 1e-6


def error(case, settings, quantity):
    traj = simulate(case.scene, case.times, settings)[0]
    return trajectory_errors(traj, case.exact(case.times))[quantity][0]


def order(case, integrator, quantity, dt):
    e1 = error(case, Settings(integrator, dt=dt), quantity)
    e2 = error(case, Settings(integrator, dt=dt / 2), quantity)
    return np.log2(e1 / e2)


@pytest.mark.parametrize("name", FREE_CASES)
@pytest.mark.parametrize("integrator,expected", [("rk4", 4), ("rkmk4", 4), ("euler", 1)])
def test_order_on_free_bodies(name, integrator, expected):
    case = make_case(name, t_final=2.0)
    dt = 1e-2 if expected == 4 else 2e-3
    assert order(case, integrator, "orientation", dt) == pytest.approx(expected, abs=ORDER_SLACK)


def test_order_on_the_rod():
    """phi(t) is quadratic, so RK4 and RKMK4 are exact up to roundoff even at dt = 0.01;
    symplectic Euler is first order."""
    case = make_case("pivoted_rod")
    for name in ("rk4", "rkmk4"):
        assert error(case, Settings(name, dt=1e-2), "joint") < 1e-12
    assert order(case, "euler", "joint", 1e-3) == pytest.approx(1.0, abs=ORDER_SLACK)


@pytest.mark.parametrize("name", FREE_CASES)
def test_newton_euler_and_kane_agree(name):
    case = make_case(name, t_final=2.0)
    runs = {f: simulate(case.scene, case.times, Settings("rk4", dt=1e-3, options={"formulation": f}))[0]
            for f in ("newton-euler", "kane", "newton-euler-matrix")}
    ne, kane, mat = (runs[k].bodies[case.scene.bodies[0].name] for k in ("newton-euler", "kane", "newton-euler-matrix"))
    assert np.max(spatial.rotation_angle(ne.quaternion, kane.quaternion)) < FORMULATION_AGREEMENT
    assert np.max(np.abs(ne.position - kane.position)) < FORMULATION_AGREEMENT * 1e3  # box falls ~20 m
    assert np.max(np.abs(ne.angular_velocity - kane.angular_velocity)) < FORMULATION_AGREEMENT
    # the rotation-matrix state: same motion to the method's own error
    assert np.max(spatial.rotation_angle(ne.quaternion, mat.quaternion)) < 1e-9


def test_matrix_state_drifts_off_the_group_unless_integrated_on_it():
    """The rotation matrix's R' = R [w]x integrated by RK4 loses orthonormality; RKMK4
    (exponential update) keeps it to roundoff."""
    case = make_case("free_top_intermediate", t_final=10.0)
    drift = {}
    for name in ("rk4", "rkmk4"):
        traj = simulate(case.scene, case.times, Settings(name, dt=1e-2, options={"formulation": "newton-euler-matrix"}))[0]
        drift[name] = np.max(orthonormality_error(case.scene, traj))
    assert drift["rkmk4"] < 1e-13
    assert drift["rk4"] > 100 * drift["rkmk4"]


def test_only_declared_effects_are_computed():
    """No gravity unless the scene has it: a force-free body does not accelerate at all."""
    top = make_case("free_top").scene
    ne = NewtonEuler(top)
    a = ne.acceleration(0.0, ne.q0, ne.v0)
    assert np.array_equal(a[:3], np.zeros(3))
    box = NewtonEuler(make_case("particle_box").scene)
    assert np.array_equal(box.acceleration(0.0, box.q0, box.v0)[:3], [0.0, 0.0, -9.8])


def test_divergence_is_returned_as_nan_not_raised():
    class Blowup:
        from dalembert.reference.configuration import Block

        blocks = (Block("vector", slice(0, 1), slice(0, 1)),)
        q0, v0 = np.array([0.0]), np.array([1.0])

        def acceleration(self, t, q, v):
            with np.errstate(over="ignore", invalid="ignore"):
                return v**3

    times = np.linspace(0, 5, 51)
    Q, V, stats = INTEGRATORS["rk4"]().run(Blowup(), times, Settings("rk4", dt=0.1))
    finite = np.isfinite(V[:, 0])
    assert finite[0] and not finite[-1]
    assert np.all(finite[: np.argmin(finite)])  # finite up to the blow-up, NaN after


@pytest.mark.parametrize("settings,field", [
    (Settings("rk4", dt=3e-3), "dt"),
    (Settings("rk4"), "dt"),
    (Settings("dop853", dt=1e-3), "dt"),
    (Settings("rk4", dt=1e-3, rtol=1e-6), "rtol"),
    (Settings("rk4", dt=1e-3, options={"bogus": 1}), "options"),
    (Settings("rk4", dt=1e-3, options={"formulation": "lagrange"}), "formulation"),
])
def test_bad_settings_fail_before_running(settings, field):
    case = make_case("pivoted_rod")
    with pytest.raises(ValueError, match=field):
        simulate(case.scene, case.times, settings)


def test_unknown_integrator_suggests():
    case = make_case("pivoted_rod")
    with pytest.raises(KeyError, match="did you mean 'rk4'"):
        simulate(case.scene, case.times, Settings("rk5", dt=1e-3))


@pytest.mark.parametrize("kw", [dict(dt=-1.0), dict(dt=float("nan")), dict(rtol=0.0), dict(atol=float("inf"))])
def test_settings_reject_non_positive_knobs(kw):
    with pytest.raises(ValueError, match=next(iter(kw))):
        Settings("rk4", **kw)


@pytest.mark.parametrize("damping", [2.0, 400.0])
def test_radau_meets_the_damped_oscillators_closed_form_and_the_decay_rate_is_its_eigenvalues(damping):
    """A box on a damped spring from the world (m = 2 kg, k = 50 N/m), released stretched at rest. Its
    eigenvalues are (-c +- sqrt(c^2 - 4 m k)) / (2 m): underdamped at c = 2 (decay rate c / (2 m) = 0.5 1/s),
    overdamped and stiff at c = 400 (-0.125 and -199.875 1/s: decay rate 199.875). The stretch is
    x0 (r2 e^(r1 t) - r1 e^(r2 t)) / (r2 - r1) (complex roots for the underdamped case)."""
    from dalembert.reference.solver import decay_rate
    from dalembert.scene import Body, Joint, Scene, Spring, Spring

    m, k, rest, x0 = 2.0, 50.0, 1.0, 0.3
    scene = Scene("oscillator", [Body.box("b", m, (0.1, 0.2, 0.3))],
                  [Joint("free", "world", "b", [0, 0, -(rest + x0), 1, 0, 0, 0], [0.0] * 6)], (0.0, 0.0, 0.0),
                  springs=[Spring("world", "b", stiffness=k, damping=damping, rest_length=rest)])
    r1, r2 = np.roots([m, damping, k]).astype(complex)
    assert decay_rate(scene) == pytest.approx(-min(r1.real, r2.real), rel=DECAY_RATE_RTOL)
    times = np.linspace(0.0, 2.0, 21)
    stretch = (x0 * (r2 * np.exp(r1 * times) - r1 * np.exp(r2 * times)) / (r2 - r1)).real
    traj = simulate(scene, times, Settings("radau", rtol=1e-12, atol=1e-12))[0]
    assert np.abs(-traj.bodies["b"].position[:, 2] - rest - stretch).max() < RADAU_TOL


def _slider_on_a_hub():
    """A hub turning about a tilted axis and a body sliding along the hub's (1, 1, 0) direction, off both
    COMs, under gravity, and a spring-damper from the world to the slider: the prismatic joint's slide, Coriolis
    and centripetal terms, and a spring with a world end."""
    hub = Body("hub", 3.0, np.diag([0.2, 0.3, 0.4]))
    slider = Body.box("slider", 0.5, (0.04, 0.02, 0.06))
    return Scene("slider_on_hub", [hub, slider],
                 [Joint("revolute", "world", "hub", (0.4,), (2.0,), axis=(0, 1, 2), parent_point=(0, 0, 0.1)),
                  Joint("prismatic", "hub", "slider", (0.2,), (0.3,), axis=(1, 1, 0), parent_point=(0, 0.1, 0.25),
                        child_point=(0.01, 0, 0))], (0.0, 0.0, -9.81),
                 springs=[Spring("world", "slider", stiffness=40.0, damping=0.5, rest_length=0.1, point_a=(0, 0, 0.3),
                                 point_b=(0.01, 0.02, 0))])


KANE_SCENES = {name: (lambda name=name: make_case(name, t_final=0.5).scene) for name in
               ["pivoted_rod", "pendulum", "chain", "heavy_top", "kovalevskaya_top", "particle_box_welded",
                "flyball_governor", "four_bar", "bricard", "n_four_bar", "andrews_squeezer"]}
KANE_SCENES.update(chain_case=lambda: chain_case(0.5).scene,
                   free_body_world_loads=lambda: free_body_world_loads_case(0.5).scene, slider_on_hub=_slider_on_a_hub)


@pytest.mark.parametrize("name", KANE_SCENES)
def test_kane_reads_every_sample_at_once_as_it_reads_them_one_by_one(name, monkeypatch):
    """The read-back's stacked solve (``Kane.sampled``; with loops, ``ClosedLoops``' projection and rank cut per
    state) gives every body's pose and velocity, every joint's reaction and every loop's force as ``_solve`` does
    one state at a time (the integrators' path), at the states of a real run (with loops, moved off its manifolds)."""
    scene = KANE_SCENES[name]()
    system = FORMULATIONS["kane"](scene)
    times = np.linspace(0.0, 0.02 if name == "andrews_squeezer" else 0.5, 26)  # (the squeezer's 0.03-s horizon)
    Q, V, _ = INTEGRATORS["dop853"]().run(system, times, Settings("dop853", rtol=1e-8, atol=1e-10))
    assert np.isfinite(Q).all() and np.isfinite(V).all()
    if scene.loops:  # (a tree has no manifold to leave)
        Q = Q + OFF_MANIFOLD * np.sin(np.arange(Q.size)).reshape(Q.shape)
        V = V + OFF_MANIFOLD * np.cos(np.arange(V.size)).reshape(V.shape)
    one_by_one = system.sampled_one_by_one(times, Q, V)
    monkeypatch.setattr(system, "sampled_one_by_one", None)  # the stacked path, not the fallback
    bodies, forces = system.sampled(times, Q, V)
    for body, expected in one_by_one[0].items():
        for key in "pRvw":
            scale = max(1.0, np.abs(expected[key]).max())
            assert np.abs(bodies[body][key] - expected[key]).max() <= STACKED_AGREEMENT * scale, (body, key)
    assert forces.keys() == one_by_one[1].keys()
    for joint, expected in one_by_one[1].items():
        assert np.abs(forces[joint] - expected).max() <= STACKED_AGREEMENT * max(1.0, np.abs(expected).max()), joint
