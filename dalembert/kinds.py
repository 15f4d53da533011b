"""The vocabulary of a scene: the world's name, the kinds of joints, loop closures, loads and collision
geometry (with the coordinates of each joint kind), and the effect tags a scene calls for and an adapter declares.

Shared by the scene's types (``dalembert.scene``) and its checks (``dalembert.scene_checks``);
``dalembert.scene`` re-exports every name, the import path users know.
"""

from __future__ import annotations

__all__ = ["WORLD", "JOINT_KINDS", "AXIS_KINDS", "LOAD_KINDS", "LOAD_FRAMES", "LOOP_KINDS", "EFFECTS", "LOOP_EFFECTS",
           "SPRING_EFFECT", "SPRING_EFFECTS", "GEOM_KINDS", "CONTACT_EFFECT", "FRICTION_EFFECT", "RESTITUTION_EFFECT",
           "CONTACT_EFFECTS"]

WORLD = "world"

# Per joint kind: (size of q0, size of v0). Coordinates:
#   free     q = (x, y, z, qw, qx, qy, qz): COM position (m) and attitude q_WB of
#            the child in world; v = (vx, vy, vz, wx, wy, wz): COM velocity in
#            world (m/s) and angular velocity w_WB_B in the child body frame (rad/s).
#   revolute q = (angle,) (rad) about `axis` in the joint frame; v = (rate,) (rad/s).
#   prismatic q = (displacement,) (m) of the child joint frame along the unit `axis` of the
#            parent joint frame (the two frames keep their relative attitude, identity; at
#            q = 0 they coincide); v = (rate,) (m/s).
#   ball     q = quaternion of the child joint frame in the parent joint frame;
#            v = relative angular velocity in the child joint frame (rad/s).
#   weld     no coordinates.
JOINT_KINDS = {"free": (7, 6), "revolute": (1, 1), "prismatic": (1, 1), "ball": (4, 3), "weld": (0, 0)}
# The kinds that take an ``axis`` (in the joint frame, any non-zero length).
AXIS_KINDS = ("revolute", "prismatic")
LOAD_KINDS = ("force", "torque")
LOAD_FRAMES = ("world", "body")
# Loop closures (``Loop``), per kind: the constraint rows in ``dalembert.closure.ROWS``.
#   ball      the two joint points coincide;
#   revolute  a ball whose frames also share the axis ``axis`` (given in the joint frames);
#   distance  the two points stay ``length`` apart (a massless rod with ball ends).
LOOP_KINDS = ("ball", "revolute", "distance")
# Every effect tag a tree scene can call for (``Scene.effects`` draws from these): what an
# adapter declares with ``effects = EFFECTS``.
EFFECTS = frozenset({"gravity"} | {f"joint:{k}" for k in JOINT_KINDS}
                    | {f"load:{w}_{k}" for w in ("follower", "world") for k in LOAD_KINDS})
# The tags of loop closures, apart: an adapter that closes loops declares them explicitly
# (``EFFECTS | LOOP_EFFECTS``), so one that builds trees only declares them unsupported.
LOOP_EFFECTS = frozenset(f"loop:{k}" for k in LOOP_KINDS)
# The tag of linear spring-dampers (``Spring``), apart for the same reason: an adapter that builds them
# declares ``EFFECTS | SPRING_EFFECTS``; every other one declares them unsupported.
SPRING_EFFECT = "spring_damper"
SPRING_EFFECTS = frozenset({SPRING_EFFECT})

# Collision geometry fixed in a body (``Geom``), per kind: its ``size`` (m) — a sphere's (radius,), a box's
# full edge lengths (sx, sy, sz) along the geom's axes (as ``Body.box`` takes them).
GEOM_KINDS = {"sphere": ("radius",), "box": ("sx", "sy", "sz")}
# The tags of contact (``ContactPair``), apart like the springs': ``contact`` wherever the scene names a pair
# that may touch, ``friction`` where a pair has a Coulomb coefficient > 0, ``restitution`` where a pair states
# a coefficient of restitution. An adapter that maps contact declares ``EFFECTS | CONTACT_EFFECTS``; every other
# one declares contact scenes unsupported.
CONTACT_EFFECT = "contact"
FRICTION_EFFECT = "friction"
RESTITUTION_EFFECT = "restitution"
CONTACT_EFFECTS = frozenset({CONTACT_EFFECT, FRICTION_EFFECT, RESTITUTION_EFFECT})
