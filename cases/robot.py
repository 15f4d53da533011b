"""Real robots from their model files (``dalembert.models``): a fixed-base arm released under gravity, a
floating-base robot tumbling in free fall with its joints moving, and a large tree.

Each scene is the file's bodies and joint tree only: what the file calls for besides (damping, friction,
limits, actuators, mimic joints: ``FileEffects``) is left out, so every engine runs the same passive
multibody system and the reference's truth is its exact motion. ``model`` is a robot of example-robot-data
(``ur5``, ``panda``, ``solo12``, ``talos``, ...: ``dalembert.models.ROBOTS``; ``pip install dalembert[robots]``)
or the path of a URDF or MJCF file of the user's own (``--param model=path/to/robot.urdf``).
"""

from __future__ import annotations

from dalembert.case import Case, Tolerance, case
from dalembert.cases._sampling import sample_times
from dalembert.models import ModelError, read_mjcf, read_urdf, robot_path
from dalembert.scene import SceneError

UNITS = dict(gravity="m/s^2", spread="rad", rate="rad/s", spin="rad/s", t_final="s", sample_interval="s")

# Default release poses (rad, in the file's joint order): joints off their zeros so that the links swing and
# the arm folds over itself (a passive, chaotic motion) while the truth stays a truth over the 2 s: its
# second solution (LSODA at 1e-12) agrees to 1.3e-11 rad on UR5, 3.6e-8 rad on Panda. (Panda released from
# (0.4, 0.9, -0.5, -1.4, 0.6, 1.2, 0.3) whips its wrist to 63 rad/s and its two solutions part to 4e-7 rad by
# 2 s: too close to ANGLE_TOL for a truth.) Other files start from ``spread`` rad on every revolute joint.
POSES = {
    "ur5": (0.3, -0.9, 1.2, -0.6, 1.1, 0.4),
    "panda": (0.0, 0.8, 0.0, -1.0, 0.0, 1.5, 0.0),
}
# Gripper fingers slide without end once the file's limits are left out: held at zero (``locked``).
LOCKED = {"panda": ("panda_finger_joint1", "panda_finger_joint2")}


def _model(case_name, model, pose, spread, base, gravity, velocities=None, rate=0.0):
    """``(ImportedModel, file path)``: the model at its pose (``pose``: comma-separated angles in the file's
    joint order; empty: ``POSES`` or ``spread`` on every joint) and joint ``rate`` (alternating signs)."""
    if not isinstance(model, str) or not model:
        raise SceneError(f"case {case_name!r}", [f"{case_name}.model: must be a robot's name or a file's path, got "
                                                 f"{model!r} — e.g. 'ur5' or path/to/robot.urdf"])
    try:
        path = robot_path(model)
        read = read_mjcf if path.endswith(".xml") else read_urdf
        kw = {} if read is read_mjcf else dict(base=base)
        bare = read(path, gravity=gravity, locked=LOCKED.get(model, ()), **kw)
        names = [n for n in bare.joint_names if n != "base"]
        if pose:
            try:
                angles = [float(v) for v in pose.split(",")]
            except ValueError:
                angles = []
            if len(angles) != len(names):
                raise SceneError(f"case {case_name!r}", [
                    f"{case_name}.pose: {len(names)} comma-separated joint coordinates wanted (rad or m, in the "
                    f"file's order: {', '.join(names)}), got {pose!r} — give one per joint"])
        else:
            angles = POSES.get(model, [spread] * len(names))
        kinds = {n: bare.scene.joint(bare.joint_names[n]).kind for n in names}
        positions = {n: a for n, a in zip(names, angles) if kinds[n] in ("revolute", "prismatic")}
        speeds = {n: rate * (-1.0) ** i for i, n in enumerate(names) if kinds[n] in ("revolute", "prismatic")}
        speeds.update(velocities or {})
        return read(path, gravity=gravity, positions=positions, velocities=speeds, locked=LOCKED.get(model, ()),
                    name=case_name, **kw), path
    except ModelError as err:
        raise SceneError(f"case {case_name!r}", [str(err)]) from None


# No closed form: the truth is the reference at its truth settings (DOP853 at rtol = atol = 1e-12 on Kane's
# formulation), cross-checked by its second solution (the contract's: LSODA at 1e-12). The swing is chaotic
# (a folding arm): the horizon is kept short so that the two agree far below the tolerances.
ANGLE_TOL = Tolerance(1e-6, "rad over 2 s: met by a 4th-order method at dt = 1e-3 (reference rk4 on UR5: 9.8e-9 "
                            "rad) but not at 5e-3 (5.8e-6) or 1e-2 (1.4e-4), by dop853 at rtol 1e-9 (6.6e-9) but not "
                            "1e-6 (5.5e-5); 8e4 times the truth's own uncertainty (its second solution, LSODA at "
                            "1e-12, agrees to 1.3e-11 rad)")
POSITION_TOL = Tolerance(1e-6, "m; the links' COMs stay within 0.85 m of the base: ANGLE_TOL times that, rounded up")
VELOCITY_TOL = Tolerance(1e-5, "m/s; COMs move at up to 6.2 m/s: ANGLE_TOL times that, rounded up")
RATE_TOL = Tolerance(5e-5, "rad/s; the wrist whips at up to 25 rad/s: ANGLE_TOL times that, doubled")
REACTION_TOL = Tolerance(1e-5, "relative to the largest joint reaction; m a - m g of the same motion: ten times "
                               "ANGLE_TOL, as accelerations are rates times rates (up to 25 rad/s)")
ENERGY_TOL = Tolerance(1e-8, "relative to max(|E(0)|, the largest kinetic energy); reference rk4 on UR5 at dt = "
                             "1e-3: 3.1e-9, at 1e-2: 3.4e-5; the truth's own drift: 2.1e-12")


def _arm_case(name, model, pose, spread, gravity, t_final, sample_interval):
    imported, _ = _model(name, model, pose, spread, "fixed", (0.0, 0.0, -float(gravity)))
    return Case(name, imported.scene, t_final, sample_times(t_final, sample_interval, name), conserved=("energy",),
                tolerances=dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                                angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL))


@case(tags=("robot", "jointed", "gravity"), units=UNITS, positive=("sample_interval",))
def robot_arm(model="ur5", pose="", spread=0.5, gravity=9.81, t_final=2.0, sample_interval=0.01):
    """A fixed-base arm released at rest under gravity from a pose: a passive, chaotic swing of a real robot
    (UR5: 6 bodies on 6 revolute joints; Panda: 10 bodies, 7 revolute joints, its hand and held fingers welded;
    the fixed base is the world's).

    ``model``: a robot of example-robot-data (``ur5``, ``panda``, ...) or a URDF/MJCF file; ``pose``:
    comma-separated joint angles in the file's order (default ``POSES``, or ``spread`` rad on every joint of
    another file). The file's damping, friction, limits and actuators are left out (``FileEffects``).
    """
    return _arm_case("robot_arm", model, pose, spread, gravity, t_final, sample_interval)


@case(tags=("robot", "variant", "jointed", "gravity"), units=UNITS, positive=("sample_interval",))
def robot_tree(model="talos", pose="", spread=0.3, gravity=9.81, t_final=0.25, sample_interval=0.01):
    """A large tree released under gravity, welded at its root: Talos (example-robot-data's
    ``talos_reduced.urdf``: 50 bodies, 32 revolute joints, 18 welds to sensors and tools) with every
    joint ``spread`` rad off its zero. The cost of many joints against the chain's; a preset of ``robot_arm``
    (tag ``variant``: out of the default matrix, and checked at its own horizon, not ``hard``'s 2 s).
    Its reference truth took 7.2 s for the 0.25 s horizon and 144 s for 1 s (on a shared 2-core machine; UR5's
    2 s: 4.8 s), hence the short horizon."""
    return _arm_case("robot_tree", model, pose, spread, gravity, t_final, sample_interval)


# Free fall without gravity: momentum and energy are exact invariants, and every drift is the integrator's.
FREE_ANGLE_TOL = Tolerance(1e-6, "rad over 1 s (joint angles and the base attitude); reference rk4 on Solo12: 2.1e-9 "
                                 "at dt = 1e-3, 1.8e-5 at 1e-2; the truth's second solution (LSODA at 1e-12) agrees "
                                 "to 7.3e-11")
FREE_POSITION_TOL = Tolerance(1e-6, "m; the bodies stay within 0.7 m of the origin: ANGLE_TOL times that, rounded up")
FREE_VELOCITY_TOL = Tolerance(1e-5, "m/s and rad/s; joints swing at up to 8.6 rad/s: ANGLE_TOL times that, rounded up")
FREE_ENERGY_TOL = Tolerance(1e-9, "relative; reference rk4 at dt = 1e-3: 9.4e-11 (at 1e-2: 8.9e-7); the truth's own "
                                  "drift: 9.2e-13")
FREE_MOMENTUM_TOL = Tolerance(1e-9, "relative; no external force or torque acts, both momenta are exact invariants: "
                                    "reference rk4 at dt = 1e-3 drifts 1.2e-10 (angular) and 1.0e-10 (linear), at "
                                    "1e-2 1.4e-6 and 1.1e-6; the truth's own: 1.0e-12")


@case(tags=("robot", "hard", "jointed", "free"), units=UNITS, positive=("sample_interval",))
def robot_free_fall(model="solo12", pose="", spread=0.4, rate=3.0, spin=(0.5, 1.0, 2.0), t_final=1.0,
                    sample_interval=0.01):
    """A floating-base robot tumbling in free fall (no gravity) with its joints moving: Solo12 (a base and four
    3-joint legs: 17 bodies, 4 of them welded feet; 18 degrees of freedom) thrown with the base spinning at
    ``spin`` (rad/s, base axes) and every joint swinging at ``rate`` rad/s (alternating signs) from
    ``spread`` rad. Momentum and energy are conserved exactly: their drift is each engine's own."""
    if not (isinstance(spin, tuple) and len(spin) == 3):
        raise SceneError("case 'robot_free_fall'", [f"robot_free_fall.spin: 3 numbers wanted (rad/s, base axes), "
                                                    f"got {spin!r} — e.g. 0.5,1,2"])
    imported, _ = _model("robot_free_fall", model, pose, spread, "free", (0.0, 0.0, 0.0),
                         velocities={"base": (0.1, 0.0, 0.2, *spin)}, rate=rate)
    return Case("robot_free_fall", imported.scene, t_final, sample_times(t_final, sample_interval, "robot_free_fall"),
                conserved=("energy", "angular_momentum", "linear_momentum"),
                tolerances=dict(joint=FREE_ANGLE_TOL, orientation=FREE_ANGLE_TOL, position=FREE_POSITION_TOL,
                                velocity=FREE_VELOCITY_TOL, angular_velocity=FREE_VELOCITY_TOL,
                                reaction_force=REACTION_TOL, energy=FREE_ENERGY_TOL,
                                angular_momentum=FREE_MOMENTUM_TOL, linear_momentum=FREE_MOMENTUM_TOL))


__all__ = ["robot_arm", "robot_tree", "robot_free_fall", "POSES", "LOCKED"]
