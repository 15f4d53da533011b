"""The falling particle box: 27 equal point masses on a 3 x 3 x 3 lattice, rigidly joined, spinning while
they fall under gravity (torque-free about the centre of mass, which falls on a parabola)."""

from __future__ import annotations

import itertools

import numpy as np

from dalembert.cases._sampling import sample_times
from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.scene import Body, Joint, Scene
from dalembert.trajectory import BodyStates, Trajectory
from dalembert.reference.closed_form import Ballistic, TorqueFreeTop

POSITION_TOL = Tolerance(1e-8, "m after a 1960 m fall; the parabola is quadratic in t, so RK methods of order >= 2 "
                               "are exact up to roundoff (~1e-13 relative)")
VELOCITY_TOL = Tolerance(1e-9, "m/s at 196 m/s; as POSITION_TOL")
ORIENTATION_TOL = Tolerance(1e-7, "rad over 20 s; a 4th-order method at dt = 1e-3 reaches ~1e-11 here, "
                                  "a 2nd-order one ~1e-6 at dt = 1e-4")
RATE_TOL = Tolerance(1e-7, "rad/s; as ORIENTATION_TOL at a spin of ~1.4 rad/s")
ENERGY_TOL = Tolerance(1e-10, "relative to the kinetic energy reached (~2e5 J): potential and kinetic "
                              "energy exchange exactly")
MOMENTUM_TOL = Tolerance(1e-10, "relative; spin angular momentum about the COM is exactly conserved")
DISTANCE_TOL = Tolerance(1e-10, "m; a rigid body keeps every pairwise distance — what drifts is the attitude "
                                "representation (quaternion norm, matrix orthonormality)")


@case(tags=("canonical", "free", "gravity", "particles"),
      units=dict(spacing="m", mass="kg", gravity="m/s^2", omega0="rad/s", t_final="s", sample_interval="s"),
      positive=("spacing", "mass", "sample_interval"))
def particle_box(spacing=(1.0, 2.0, 3.0), mass=10.0, gravity=9.8, omega0=(0.0, 1.0, 1.0), t_final=20.0,
                 sample_interval=0.01):
    """27 equal point masses, total ``mass``, on the lattice ``(a i, b j, c k)``,
    ``i, j, k`` in {0, 0.5, 1}, rigidly joined, spinning at ``omega0`` (body
    frame, axes along the lattice) while the COM falls from rest at the origin.

    Principal moments 65/3, 50/3, 25/3 kg m^2 for the defaults (the inertia tensor of the lattice,
    ``dalembert.scene.mass_properties``; tests/test_closed_forms.py).
    """
    a = np.asarray(spacing, dtype=float)
    grid = np.array(list(itertools.product((0.0, 0.5, 1.0), repeat=3))) * a
    body, _com = Body.from_point_masses("box", np.full(len(grid), mass / len(grid)), grid)
    g = (0.0, 0.0, -float(gravity))
    scene = Scene(
        "particle_box",
        bodies=[body],
        joints=[Joint("free", "world", "box", q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0, 0, *omega0])],
        gravity=g,
    )
    com = Ballistic((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), g)
    # Uniform gravity exerts no torque about the COM: sum_i u_i x m_i g = (sum_i m_i u_i) x g,
    # and the first moment about the COM, sum_i m_i u_i, is zero. So the box turns exactly
    # like the torque-free body while its COM falls (the rotation about the COM obeys the
    # torque about it alone; Landau & Lifshitz, Mechanics, section 34).
    spin = TorqueFreeTop(body.inertia_matrix, np.asarray(omega0, dtype=float))

    def truth(t):
        t = np.asarray(t, dtype=float)
        return Trajectory(t, {"box": BodyStates(com.position(t), spin.quaternion(t), com.velocity(t),
                                                spin.angular_velocity_world(t))})

    return Case(
        "particle_box", scene, t_final, sample_times(t_final, sample_interval, "particle_box"), exact=truth,
        conserved=("energy", "angular_momentum_com", "pairwise_distance"),
        tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL, orientation=ORIENTATION_TOL,
                        angular_velocity=RATE_TOL, energy=ENERGY_TOL, angular_momentum_com=MOMENTUM_TOL,
                        pairwise_distance=DISTANCE_TOL),
    )


WELDED_ORIENTATION_TOL = Tolerance(1e-6, "rad over 2 s; Exudyn's generalized-alpha (second order) on the 26 welds "
                                         "reaches 2.7e-7 after 1 s at dt = 1e-3; engines that merge welds reach "
                                         "roundoff (~1e-14)")
WELDED_POSITION_TOL = Tolerance(1e-6, "m: the outer particles sit up to 1.9 m from the COM, so "
                                      "WELDED_ORIENTATION_TOL times that radius, rounded up")
WELDED_DISTANCE_TOL = Tolerance(1e-8, "m; the welds must hold: an index-3 solver enforces them at its Newton "
                                      "tolerance (measured 1.8e-15 m), a merged rigid body keeps them exactly")
# Stability bounds of the hard case (not the rigid box's 1e-10 accuracy bounds, which made
# scipy's DOP853 at rtol 1e-6 "drift"): an integrator that follows the motion to
# WELDED_ORIENTATION_TOL changes energy and spin by about as much.
WELDED_ENERGY_TOL = Tolerance(1e-6, "relative; as WELDED_ORIENTATION_TOL: first-order methods lose 5e-4 over "
                                    "2 s at dt = 1e-3, fourth-order ones hold it to ~1e-13")
WELDED_MOMENTUM_TOL = Tolerance(1e-6, "relative, spin about the COM; as WELDED_ENERGY_TOL")


@case(tags=("hard", "free", "gravity", "particles", "constraints"),
      units=dict(spacing="m", mass="kg", gravity="m/s^2", omega0="rad/s", t_final="s", radius="m",
                 sample_interval="s"),
      positive=("spacing", "mass", "radius", "sample_interval"))
def particle_box_welded(spacing=(1.0, 2.0, 3.0), mass=10.0, gravity=9.8, omega0=(0.0, 1.0, 1.0), t_final=2.0,
                        radius=0.05, sample_interval=0.01):
    """The particle box as 27 separate bodies: the centre particle free, the 26
    others welded to it (a star of weld joints). Each particle is a small solid
    sphere of ``radius`` (its own inertia ``2/5 m r^2`` keeps every body's inertia
    positive definite, and is part of the truth).

    Engines that merge welds into one body (MuJoCo, Pinocchio, the reference)
    must reproduce the rigid box exactly; engines that hold them by constraints
    (Exudyn with ``joints=redundant``) show the constraint drift in the
    pairwise distances. Closed kinematic loops are not in the scene vocabulary
    yet, so the constraints here form a tree.
    """
    a = np.asarray(spacing, dtype=float)
    grid = np.array(list(itertools.product((0.0, 0.5, 1.0), repeat=3))) * a
    m = mass / len(grid)
    com0 = grid.mean(axis=0)
    u = grid - com0  # each particle relative to the COM, box axes
    sphere = 0.4 * m * radius**2
    names = [f"p{i}{j}{k}" for i, j, k in itertools.product(range(3), repeat=3)]
    centre = names[13]  # p111, at the COM
    bodies = [Body(n, m, np.eye(3) * sphere, particles=((m, (0.0, 0.0, 0.0)),)) for n in names]
    joints = [Joint("free", "world", centre, q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0, 0, *omega0])]
    joints += [Joint("weld", centre, n, parent_point=tuple(ui)) for n, ui in zip(names, u) if n != centre]
    g = (0.0, 0.0, -float(gravity))
    scene = Scene("particle_box_welded", bodies=bodies, joints=joints, gravity=g)
    I_box = sum(m * ((ui @ ui) * np.eye(3) - np.outer(ui, ui)) for ui in u) + len(u) * sphere * np.eye(3)
    com = Ballistic((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), g)
    spin = TorqueFreeTop(I_box, np.asarray(omega0, dtype=float))

    def truth(t):
        t = np.asarray(t, dtype=float)
        q, w = spin.quaternion(t), spin.angular_velocity_world(t)
        R = spatial.quat_to_matrix(q)
        p, v = com.position(t), com.velocity(t)
        states = {}
        for n, ui in zip(names, u):
            r = R @ ui
            states[n] = BodyStates(p + r, q, v + np.cross(w, r), w)
        return Trajectory(t, states)

    return Case(
        "particle_box_welded", scene, t_final, sample_times(t_final, sample_interval, "particle_box_welded"),
        exact=truth, conserved=("energy", "angular_momentum_com", "pairwise_distance"),
        tolerances=dict(position=WELDED_POSITION_TOL, velocity=WELDED_POSITION_TOL,
                        orientation=WELDED_ORIENTATION_TOL, angular_velocity=WELDED_ORIENTATION_TOL,
                        energy=WELDED_ENERGY_TOL, angular_momentum_com=WELDED_MOMENTUM_TOL,
                        pairwise_distance=WELDED_DISTANCE_TOL),
    )
