"""Frame and convention probes: angular velocity in world axes, quaternions scalar first, a revolute axis in its
parent's joint frame, the reaction's sign and the body it acts on (``dalembert.spatial``'s conventions)."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.engine_check import ROUNDOFF_REL_TOL, Problem, probe, scenes
from dalembert.engine_check.probes_motion import _v, samples

__all__ = ["ATTITUDE_TOL", "ANGVEL_REL_TOL", "AXIS_REL_TOL", "POSE_TOL", "REACTION_REL_TOL"]

# rad: a steady spin's attitude, q(t) = q0 exp(w t / 2), is exact for an integrator on the group and within
# ~(w dt)^2 w t ~ 1e-5 rad for a first-order one on the quaternion over 0.5 s; a convention error is O(1) rad.
ATTITUDE_TOL = 1e-3
# A spin about a principal axis keeps w exactly (the gyroscopic term is zero): roundoff only.
ANGVEL_REL_TOL = ROUNDOFF_REL_TOL
# A hinge turns about its axis only: the rate about any other axis is roundoff.
AXIS_REL_TOL = ROUNDOFF_REL_TOL
# m: the initial pose from the joint's frames and q0 (forward kinematics, exact): roundoff on the probe's 1 m
# lengths, in float32 too (6e-8 m).
POSE_TOL = 1e-6
# A rod hanging at rest is in static equilibrium: the joint holds it with m g exactly (roundoff only).
REACTION_REL_TOL = ROUNDOFF_REL_TOL

_ANGVEL_LOOK_AT = ("Trajectory.angular_velocity is w_WB_W, in world axes (spatial.body_to_world(q, w_B)); a free "
                   "joint's v0 gives w in body axes (w_WB_B): turn it into the engine's convention for the initial "
                   "state, and back to world axes in the read-back")


@probe("spin_frames")
def spin_frames(ctx):
    """A tilted body spinning about its symmetry axis: quaternions w, x, y, z and angular velocity in world axes."""
    rate = 4.0
    scene = scenes.tilted_spin(rate)
    traj = ctx.trajectory(scene, samples())
    b = traj.bodies["top"]
    q0 = np.array(scenes.TILT)
    w_B = np.array([0.0, 0.0, rate])
    w_W = spatial.quat_to_matrix(q0) @ w_B
    start = float(spatial.rotation_angle(b.quaternion[0], q0))
    if start > ATTITUDE_TOL:
        if float(spatial.rotation_angle(spatial.xyzw_to_wxyz(b.quaternion[0]), q0)) <= ATTITUDE_TOL:
            return [Problem("spin_frames", f"quaternion order x, y, z, w: the first sample {_v(b.quaternion[0])} is "
                            f"the scene's attitude {_v(q0)} with the scalar last",
                            "Trajectory quaternions are scalar first (w, x, y, z): spatial.xyzw_to_wxyz in the "
                            "read-back, and spatial.wxyz_to_xyzw where the engine takes x, y, z, w")]
        return [Problem("spin_frames", f"the first sample's attitude {_v(b.quaternion[0])} is {start:.3g} rad from "
                        f"the scene's {_v(q0)}", "the initial state: a free joint's q0 is (x, y, z, qw, qx, qy, qz), "
                        "q_WB scalar first, of the body frame B (origin at the COM)")]
    off = float(np.max(np.linalg.norm(b.angular_velocity - w_W, axis=1)) / rate)
    if off > ANGVEL_REL_TOL:
        if float(np.max(np.linalg.norm(b.angular_velocity - w_B, axis=1)) / rate) <= ANGVEL_REL_TOL:
            return [Problem("spin_frames", f"angular velocity in the wrong frame: the trajectory gives {_v(w_B)} rad/s, "
                            f"the spin in body axes; in world axes it is {_v(w_W)}", _ANGVEL_LOOK_AT)]
        return [Problem("spin_frames", f"angular velocity off by {off:.3g} of the spin: it stays {_v(w_W)} rad/s "
                        "(world axes) on a spin about a principal axis", _ANGVEL_LOOK_AT)]
    exact = spatial.quat_multiply(q0, spatial.quat_exp(traj.t[:, None] * w_B))
    drift = spatial.rotation_angle(b.quaternion, exact)
    if float(np.max(drift)) > ATTITUDE_TOL:
        k = int(np.argmax(drift))
        return [Problem("spin_frames", f"the attitude leaves the exact spin q0 exp(w_B t / 2): {drift[k]:.3g} rad off "
                        f"at t = {traj.t[k]:g} s", "the attitude's update (q' = q w_B / 2, body axes, scalar first) "
                        "and its read-back")]
    return []


@probe("hinge_axis")
def hinge_axis(ctx):
    """A hinge whose axis (1, 0, 0) is given in a joint frame turned 90 deg about z turns about world y, about its
    pivot, from the pose its frames and q0 give."""
    p = scenes.Pendulum(0.3)
    traj = ctx.trajectory(p.scene, samples(0.2))
    b = traj.bodies["rod"]
    expected = spatial.initial_body_states(p.scene)["rod"]
    problems = []
    frames = ("the joint frames: parent_point/parent_quat in the parent's frame, child_point/child_quat in the "
              "child's, q0 about the axis in the joint frame")
    if float(np.linalg.norm(b.position[0] - expected["p"])) > POSE_TOL:
        problems.append(Problem("hinge_axis", f"the hinged rod starts at {_v(b.position[0])} m, expected "
                                f"{_v(expected['p'])} (its joint frames at q0 = 0.3 rad)", frames))
    turned = float(spatial.rotation_angle(b.quaternion[0], spatial.matrix_to_quat(expected["R"])))
    if turned > ATTITUDE_TOL:
        problems.append(Problem("hinge_axis", f"the hinged rod's first attitude is {turned:.3g} rad from its joint "
                                "frames' at q0 = 0.3 rad (the child frame turned 30 deg about the rod)",
                                frames + "; and the quaternion's order (w, x, y, z: spin_frames)"))
    w = b.angular_velocity
    across = w - np.outer(w @ p.axis_W, p.axis_W)
    scale = float(np.max(np.linalg.norm(w, axis=1)))
    if scale > 0.0 and float(np.max(np.linalg.norm(across, axis=1))) > AXIS_REL_TOL * scale:
        k = int(np.argmax(np.linalg.norm(w, axis=1)))
        problems.append(Problem("hinge_axis", f"the hinge turns about {_v(w[k] / np.linalg.norm(w[k]))} (world), not "
                                f"its axis {_v(p.axis_W)}: (1, 0, 0) in a joint frame turned 90 deg about z",
                                "the revolute axis is given in the joint frame: turn it by parent_quat into the "
                                "parent's frame (not the world's, not the child's)"))
    pivot = np.array(p.joint.parent_point)
    arm = np.linalg.norm(b.position - pivot, axis=1)
    if float(np.max(np.abs(arm - p.arm))) > POSE_TOL + AXIS_REL_TOL * p.arm:
        problems.append(Problem("hinge_axis", f"the rod's COM does not stay {p.arm:g} m from the pivot (it ranges "
                                f"{arm.min():.6g}..{arm.max():.6g} m)", "the joint's points: parent_point (parent "
                                "frame) and child_point (child frame) are the same point"))
    return problems


@probe("reaction_sign")
def reaction_sign(ctx):
    """A rod hanging at rest: the joint's reaction is m g up, on the child."""
    p = scenes.Pendulum(0.0)
    traj = ctx.trajectory(p.scene, samples(0.05))
    key = "reaction_force:rod"
    if key not in traj.extras:
        ctx.notes.append(f"reports no {key}: reactions not measured")
        return []
    seen = np.asarray(traj.extras[key], dtype=float)
    up = np.array([0.0, 0.0, p.mass * scenes.STANDARD_G])
    err = float(np.max(np.linalg.norm(seen - up, axis=1)))
    if err <= REACTION_REL_TOL * up[2]:
        return []
    if float(np.max(np.linalg.norm(seen + up, axis=1))) <= REACTION_REL_TOL * up[2]:
        return [Problem("reaction_sign", f"reaction sign flipped: a rod hanging at rest has {_v(seen[0])} N from its "
                        f"joint; the joint holds it up with m g = {_v(up)} N",
                        f"{key} is the force the joint exerts ON the child (world axes, N): negate the engine's "
                        "force on the parent, or take the child's")]
    return [Problem("reaction_sign", f"a rod hanging at rest has {_v(seen[0])} N from its joint, expected m g up = "
                    f"{_v(up)} N", f"{key}: the force the joint exerts on the child, world axes, N (not the body "
                    "frame's, not a torque, not the parent's)")]
