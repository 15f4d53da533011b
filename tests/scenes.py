"""Extra scenes shared by tests: ones that exercise every frame conversion of an adapter, and spatial chains closed
to the world by a loop."""

import numpy as np

from dalembert import closure, spatial
from dalembert.case import Case, Tolerance
from dalembert.scene import Body, Joint, Load, Loop, Scene


def full_inertia_body(name, mass, moments, theta):
    """A body whose frame is not principal: inertia R diag(moments) R^T."""
    R = spatial.so3_exp(theta)
    return Body(name, mass, R @ np.diag(moments) @ R.T)


def chain_case(t_final=1.0):
    """A ball-jointed body hanging from the world under gravity, a welded body
    below it, a revolute body below that; off-centre joint frames, rotated
    joint frames, full inertia tensors, and all four kinds of load."""
    a = full_inertia_body("a", 2.0, (0.3, 0.4, 0.5), (0.3, -0.2, 0.5))
    b = full_inertia_body("b", 0.5, (0.05, 0.06, 0.08), (-0.4, 0.1, 0.2))
    c = full_inertia_body("c", 1.0, (0.1, 0.15, 0.2), (0.2, 0.7, -0.1))
    q_ball = spatial.quat_exp([0.2, -0.1, 0.3])
    scene = Scene(
        "chain",
        bodies=[a, b, c],
        joints=[
            Joint("ball", "world", "a", q0=q_ball, v0=[0.5, -1.0, 2.0], parent_point=[0.1, 0.0, 1.0],
                  parent_quat=spatial.quat_exp([0.0, 0.3, 0.0]), child_point=[0.0, 0.05, 0.4],
                  child_quat=spatial.quat_exp([0.1, 0.0, -0.2])),
            Joint("weld", "a", "b", parent_point=[0.0, 0.0, -0.3], parent_quat=spatial.quat_exp([0.5, 0.0, 0.0]),
                  child_point=[0.1, 0.0, 0.1]),
            Joint("revolute", "b", "c", q0=[0.4], v0=[-3.0], axis=[0.0, 1.0, 1.0], parent_point=[0.0, 0.2, -0.1],
                  child_point=[0.0, 0.0, 0.35], child_quat=spatial.quat_exp([0.0, 0.0, 0.4])),
        ],
        loads=[Load("a", "force", [0.0, 3.0, 0.0], "body", point=[0.2, 0.0, 0.0]),
               Load("c", "force", [1.0, 0.0, 0.5], "world", point=[0.0, 0.1, 0.0]),
               Load("b", "torque", [0.0, 0.0, 0.4], "body"),
               Load("c", "torque", [0.2, 0.0, 0.0], "world")],
        gravity=[0.0, 0.0, -9.81],
    )
    times = np.linspace(0.0, t_final, int(round(t_final / 0.01)) + 1)
    return Case("chain", scene, t_final, times, tolerances={"orientation": Tolerance(1e-6, "test")})


def free_body_world_loads_case(t_final=1.0):
    """A free body with a full inertia, a world force off its COM and a world torque, under gravity."""
    body = full_inertia_body("f", 1.5, (0.2, 0.3, 0.45), (0.1, 0.2, 0.3))
    scene = Scene(
        "free_world_loads",
        bodies=[body],
        joints=[Joint("free", "world", "f", q0=[0.1, 0.2, 0.3, *spatial.quat_exp([0.3, 0.1, -0.2])],
                      v0=[0.5, 0.0, 1.0, 1.0, -2.0, 3.0])],
        loads=[Load("f", "force", [0.0, 2.0, 0.0], "world", point=[0.3, 0.0, 0.1]),
               Load("f", "torque", [0.0, 0.0, 0.5], "world")],
        gravity=[0.0, 0.0, -9.81],
    )
    times = np.linspace(0.0, t_final, int(round(t_final / 0.01)) + 1)
    return Case("free_world_loads", scene, t_final, times, tolerances={"orientation": Tolerance(1e-6, "test")})


def cart_pendulum():
    """A cart on an inclined prismatic joint to the world (turned parent frame, offset points) and a pendulum
    hinged under it: the slide and the swing exchange momentum."""
    cart, rod = Body.box("cart", 2.0, (0.3, 0.2, 0.1)), Body.cylinder("rod", 0.5, 0.8, 0.02, axis=2)
    return Scene("cart_pendulum", (cart, rod),
                 (Joint("prismatic", "world", "cart", (0.1,), (0.4,), axis=(1.0, 0.0, 0.2),
                        parent_point=(0.0, 0.1, 1.0), parent_quat=spatial.quat_exp([0.0, 0.0, 0.3]),
                        child_point=(0.02, 0.0, -0.01)),
                  Joint("revolute", "cart", "rod", (0.6,), (-1.0,), axis=(0.0, 1.0, 0.0),
                        parent_point=(0.0, 0.0, -0.05), child_point=(0.0, 0.0, 0.4))),
                 (0.0, 0.0, -9.81))


def spatial_chain(kind):
    """Four 0.5-m, 1-kg rods hanging from the world by revolute joints whose axes alternate between x
    and y (a spatial chain), the last rod's tip closed to the world: by a ``ball`` at its initial place
    (4 speeds - 3 rows: one degree of freedom) or by a ``distance`` loop to an anchor 0.36 m away (three).
    The initial joint rates lie in the loop Jacobian's null space (the fastest joint at 2 rad/s), so the
    loop closes at velocity level too."""
    length, axes, q0 = 0.5, ([1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0]), (0.3, -0.4, 0.5, 0.2)
    names = [f"l{i}" for i in range(4)]
    bodies = [Body.cylinder(n, 1.0, length, 0.02, axis=2) for n in names]
    joints = [Joint("revolute", "world" if i == 0 else names[i - 1], n, q0=[q0[i]], v0=[0.0], axis=axes[i],
                    parent_point=[0, 0, 0] if i == 0 else [0, 0, -length / 2], child_point=[0, 0, length / 2])
              for i, n in enumerate(names)]
    gravity = [0.0, 0.0, -9.81]
    s0 = spatial.initial_body_states(Scene("tree", bodies, joints, gravity))
    tip = s0["l3"]["p"] + s0["l3"]["R"] @ np.array([0, 0, -length / 2])
    if kind == "ball":
        loop = Loop("ball", "world", "l3", point_a=tip, point_b=[0, 0, -length / 2], name="tip")
    else:
        anchor = tip + np.array([0.3, 0.2, 0.0])
        loop = Loop("distance", "world", "l3", point_a=anchor, point_b=[0, 0, -length / 2],
                    length=np.linalg.norm(anchor - tip), name="tip")
    at_rest = Scene("at_rest", bodies, joints, gravity, loops=[loop])
    _, J = closure.tree_jacobians(at_rest)
    r = closure.initial_rows(at_rest)[0]
    null = np.linalg.svd(r.G_a @ J["world"] + r.G_b @ J["l3"])[2][-1]
    rates = 2.0 * null / np.abs(null).max()
    joints = [Joint(**{**j.__dict__, "v0": (rates[i],)}) for i, j in enumerate(joints)]
    return Scene(f"chain_{kind}", bodies, joints, gravity, loops=[loop])
