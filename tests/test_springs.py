"""Linear spring-dampers (``Spring``): validation, serialisation, effects, and the reference against closed
forms (the harmonic oscillator, the damped one under gravity, two bodies on a spring) and exact invariants
(angular momentum about a fixed attachment point, the energy balance with the damper's dissipation)."""

from __future__ import annotations

import numpy as np
import pytest

from dalembert import invariants
from dalembert.case import Case, Tolerance
from dalembert.reference import simulate
from dalembert.scene import SPRING_EFFECTS, Body, Joint, Scene, SceneError, Spring
from dalembert.settings import Settings

MASS, STIFFNESS, REST = 2.0, 50.0, 1.0  # kg, N/m, m: omega = 5 rad/s
STRETCH = 0.3  # m, the initial stretch
DAMPING = 2.0  # N s/m: zeta = 0.1
GRAVITY = 9.81
TIMES = np.linspace(0.0, 2.0, 201)  # 1.6 periods; the steps below divide the 0.01-s sample interval
STEPS = (1e-2, 5e-3)
# RK4 halving its step: the error falls ~16-fold for a fourth-order method (measured 16.0 on the oscillators,
# 15.7 and 19.0 on the tumbling box's momentum and energy, still approaching the asymptote); a third-order error
# falls 8-fold, a fifth-order 32-fold, and a force or lever wrong at first order does not converge at all.
ORDER_RATIO = (12.0, 24.0)
# RK4 at dt = 5e-3: measured 7.8e-9 m on the 5-rad/s oscillator (less damped), 3.0e-8 m on the 6.5-rad/s pair.
POSITION_TOL = 5e-8
# The pair's linear momentum is linear in the state, and the spring's forces are equal and opposite: RK4 keeps
# it to roundoff (measured ~1e-16 kg m/s).
MOMENTUM_TOL = 1e-12
# Energy with the damper's dissipation, integrated by Simpson's rule on the 0.01-s samples of a power that
# oscillates at 2 omega = 10 rad/s: ~(0.1)^4 / 180 ~ 5e-7 of it (measured 4.6e-7 of the kinetic energy, the
# same at dt = 1e-3: the quadrature's, not the integrator's); without the term the energy falls by ~60 %.
BALANCE_TOL = 1e-6
# The off-centre spring's tumbling box: at dt = 1e-2 the energy drift is still short of the asymptote (it falls
# 21.7-fold to 5e-3), so its steps are halved once more.
TUMBLING_STEPS = (5e-3, 2.5e-3)
# ... where the relative angular momentum about the fixed end and the energy drift are measured below 1e-8; a
# wrong lever would change them at O(1).
OFF_CENTRE_TOL = 1e-7


def _box(name="b", mass=MASS):
    return Body.box(name, mass, (0.1, 0.2, 0.3))


def _oscillator(damping=0.0, gravity=0.0, point_b=(0.0, 0.0, 0.0), w0=(0.0, 0.0, 0.0), name="osc"):
    """A box on a spring from the world origin; the COM starts ``REST + STRETCH`` (+ the sag under gravity)
    away along -z (gravity along -z), at rest (angular velocity ``w0``, body axes)."""
    sag = MASS * gravity / STIFFNESS
    z0 = -(REST + sag + STRETCH)
    return Scene(name, [_box()], [Joint("free", "world", "b", q0=[0, 0, z0, 1, 0, 0, 0], v0=[0, 0, 0, *w0])],
                 [0.0, 0.0, -gravity],
                 springs=[Spring("world", "b", point_b=point_b, stiffness=STIFFNESS, damping=damping, rest_length=REST)])


def _damped_stretch(t, damping):
    """The stretch beyond the equilibrium of ``m l'' + c l' + k (l - l_eq) = 0`` from rest at ``STRETCH`` (m)."""
    omega = np.sqrt(STIFFNESS / MASS)
    zeta = damping / (2.0 * np.sqrt(STIFFNESS * MASS))
    omega_d = omega * np.sqrt(1.0 - zeta**2)
    return STRETCH * np.exp(-zeta * omega * t) * (np.cos(omega_d * t) + zeta * omega / omega_d * np.sin(omega_d * t))


@pytest.mark.parametrize("formulation", ["newton-euler", "kane"])
@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_oscillator_converges_to_its_closed_form_at_fourth_order(formulation, damping, gravity):
    """Undamped without gravity: l0 + a cos(w t); damped under gravity: the exponentially decaying closed form
    about the sagged equilibrium."""
    scene = _oscillator(damping, gravity)
    sag = MASS * gravity / STIFFNESS
    exact_z = -(REST + sag + _damped_stretch(TIMES, damping))
    errors = []
    for dt in STEPS:
        traj = simulate(scene, TIMES, Settings("rk4", dt=dt, options={"formulation": formulation}))[0]
        errors.append(np.abs(traj.bodies["b"].position[:, 2] - exact_z).max())
        assert np.abs(traj.bodies["b"].position[:, :2]).max() == 0.0  # the force stays on the line
    assert ORDER_RATIO[0] < errors[0] / errors[1] < ORDER_RATIO[1], errors
    assert errors[1] < POSITION_TOL


def test_damped_energy_falls_by_the_dissipated_energy():
    scene = _oscillator(DAMPING, GRAVITY)
    traj = simulate(scene, TIMES, Settings("rk4", dt=STEPS[1]))[0]
    ke = invariants.kinetic_energy(scene, traj).max()
    energy = invariants.total_energy(scene, traj)
    assert (energy[0] - energy[-1]) / ke > 0.5  # the damper takes most of it
    assert invariants.drift("energy_balance", scene, traj) < BALANCE_TOL
    dissipated = invariants.dissipated_energy(scene, traj)
    assert np.all(np.diff(dissipated) > 0.0)
    assert invariants.spring_energy(scene, traj)[0] == pytest.approx(0.5 * STIFFNESS * (STRETCH + MASS * GRAVITY
                                                                                         / STIFFNESS) ** 2, rel=1e-15)


def test_two_bodies_oscillate_at_the_reduced_mass_frequency_and_keep_their_momenta():
    """Two boxes (2 kg and 3 kg) on a spring between their COMs, pulled apart along x: the separation is
    REST + STRETCH cos(sqrt(k / mu) t) with mu = m1 m2 / (m1 + m2); the force is internal."""
    m1, m2 = 2.0, 3.0
    x2 = REST + STRETCH
    scene = Scene("pair", [_box("a", m1), _box("b", m2)],
                  [Joint("free", "world", "a", q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0]),
                   Joint("free", "world", "b", q0=[x2, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0])], [0, 0, 0],
                  springs=[Spring("a", "b", stiffness=STIFFNESS, rest_length=REST)])
    traj = simulate(scene, TIMES, Settings("rk4", dt=STEPS[1]))[0]
    separation = traj.bodies["b"].position[:, 0] - traj.bodies["a"].position[:, 0]
    omega = np.sqrt(STIFFNESS * (m1 + m2) / (m1 * m2))
    assert np.abs(separation - (REST + STRETCH * np.cos(omega * TIMES))).max() < POSITION_TOL
    p = invariants.linear_momentum(scene, traj)
    assert np.abs(p - p[0]).max() < MOMENTUM_TOL


@pytest.mark.parametrize("formulation", ["newton-euler", "kane"])
def test_an_off_centre_spring_keeps_the_momentum_about_its_fixed_end_and_the_energy(formulation):
    """A tumbling box hung by a point off its centre: the spring's force passes through its fixed end, so the
    angular momentum about that point is constant, whatever the lever (a moment taken about the wrong point, or
    with the wrong lever, makes it change at first order); it and the energy, the spring's included, converge at
    fourth order to constant (both are quadratic in the state, which RK4 keeps only to its order)."""
    scene = _oscillator(point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    momentum, energy = [], []
    for dt in TUMBLING_STEPS:
        traj = simulate(scene, TIMES, Settings("rk4", dt=dt, options={"formulation": formulation}))[0]
        L = invariants.angular_momentum_about(scene, traj, (0.0, 0.0, 0.0))
        momentum.append(np.linalg.norm(L - L[0], axis=1).max() / np.linalg.norm(L, axis=1).max())
        energy.append(invariants.drift("energy", scene, traj))
    for drifts in (momentum, energy):
        assert ORDER_RATIO[0] < drifts[0] / drifts[1] < ORDER_RATIO[1], (momentum, energy)
    assert momentum[1] < OFF_CENTRE_TOL and energy[1] < OFF_CENTRE_TOL


def test_bad_springs_are_refused_each_naming_its_field():
    body, joint = _box(), Joint("free", "world", "b", q0=[1, 0, 0, 1, 0, 0, 0], v0=[0] * 6)
    springs = [Spring("world", "bb", stiffness=1.0),
               Spring("b", "b", point_a=(0, 0), stiffness=-1.0, damping=float("nan")),
               Spring("world", "b", name="s"), Spring("world", "b", stiffness=1.0, name="s")]
    with pytest.raises(SceneError) as e:
        Scene("bad", [body], [joint], [0, 0, 0], springs=springs)
    msg = str(e.value)
    assert "springs[0] ('spring_world_bb': 'world' -> 'bb').body_b: no body named 'bb' — did you mean 'b'?" in msg
    assert "springs[1] ('spring_b_b': 'b' -> 'b'): joins a body to itself" in msg
    assert "springs[1] ('spring_b_b': 'b' -> 'b').point_a: needs 3 numbers" in msg
    assert "springs[1] ('spring_b_b': 'b' -> 'b').stiffness: must be finite and >= 0 (N/m), got -1.0" in msg
    assert "springs[1] ('spring_b_b': 'b' -> 'b').damping: must be finite and >= 0 (N s/m), got nan" in msg
    assert "springs[2] ('s': 'world' -> 'b'): stiffness and damping are both zero" in msg
    assert "springs: name 's' used twice" in msg


def test_a_spring_whose_points_coincide_is_refused():
    joint = Joint("free", "world", "b", q0=[1, 0, 0, 1, 0, 0, 0], v0=[0] * 6)
    with pytest.raises(SceneError, match=r"springs\[0\] .*: its points are 0 m apart at the initial state"):
        Scene("s", [_box()], [joint], [0, 0, 0], springs=[Spring("world", "b", point_a=(1, 0, 0), stiffness=1.0)])


def test_json_round_trips_springs_and_a_scene_without_has_none():
    scene = _oscillator(DAMPING, GRAVITY)
    back = Scene.from_json(scene.to_json())
    assert back.springs == scene.springs and back.springs[0].name == "spring_world_b"
    plain = Scene("plain", scene.bodies, scene.joints, scene.gravity)
    assert "springs" not in plain.to_json()  # cases without springs keep their data, and their versions


def test_a_damped_case_cannot_claim_its_energy_is_conserved():
    scene = _oscillator(DAMPING)
    tol = Tolerance(1e-6, "relative; a test bound")
    with pytest.raises(SceneError, match=r"conserved\[0\]: 'energy' is not conserved: the springs 'spring_world_b' "
                                         r"\(damping 2 N s/m\) dissipate it — list 'energy_balance'"):
        Case("damped", scene, 1.0, [0.0, 1.0], conserved=("energy",), tolerances=dict(energy=tol))
    Case("damped", scene, 1.0, [0.0, 1.0], conserved=("energy_balance",), tolerances=dict(energy_balance=tol))


def test_springs_are_an_effect_of_their_own_that_only_the_reference_runs():
    from dalembert.adapters.registry import get_adapter

    scene = _oscillator()
    assert "spring_damper" in scene.effects and SPRING_EFFECTS == {"spring_damper"}
    ref = get_adapter("reference")
    assert ref.unsupported(scene, Settings("rk4", dt=0.01)) is None
    reason = ref.unsupported(scene, Settings("rk4", dt=0.01, options={"formulation": "planar"}))
    assert "no spring-dampers" in reason
    for engine in ("mujoco", "mjx"):  # exudyn, pinocchio, drake build them (tests/test_<engine>_springs.py)
        try:
            adapter = get_adapter(engine)
        except Exception:  # an optional engine not installed
            continue
        reason = adapter.unsupported(scene, Settings(next(iter(adapter.integrators)), dt=0.01))
        assert "spring_damper" in reason and "spring-dampers between two points: not yet built" in reason, engine
