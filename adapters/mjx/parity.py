"""MJX against MuJoCo C at the same settings: one step, and over the horizon.

``one_step`` steps both engines once (or a few times) from the same initial
state of the same compiled model and returns the largest differences in
``qpos`` and ``qvel``. ``horizon`` runs both adapters on a case and returns the
largest differences between the two trajectories (orientation as the geodesic
angle, rad; COM position, m), set against the case's double-precision floor
(``Case.floor``) and, for the torque-free top, the float32 floor from the same
roundoff machinery (``dalembert.reference.roundoff.top_roundoff`` with float32
as the working and double as the extended precision).
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["one_step", "horizon"]


def one_step(case, settings, n_steps=1):
    """Largest ``|qpos_MJX - qpos_C|`` and ``|qvel_MJX - qvel_C|`` after ``n_steps`` steps from the case's
    initial state: ``dict(qpos=..., qvel=...)`` (the engine's units: m, rad, quaternion components, m/s, rad/s).

    MJX steps through the adapter's own compiled rollout (one interval of ``n_steps`` steps, the rest of the
    chunk empty), so it is the program a run of the case executes, and no second one is compiled for it."""
    import jax
    import mujoco

    from dalembert.adapters import get_adapter
    from dalembert.adapters.mjx.stepping import chunks, precision, run_rollout

    p = get_adapter("mjx").prepare(case.scene, case.times, settings)
    with precision(p.precision):
        # put where a run's steps are (``p.steps_device``): JAX compiles host steps again, as another program
        on = next(iter(p.steps_device[0].devices()))
        Q, V, _ = run_rollout(p.mx, p.dx0, [jax.device_put(c, on) for c in chunks([n_steps])])
        qpos, qvel = np.asarray(Q[0][0], dtype=float), np.asarray(V[0][0], dtype=float)
    model, data = p.model, mujoco.MjData(p.model)
    data.qpos[:], data.qvel[:] = p.qpos0, p.qvel0
    if p.load_path == "actuator":
        data.ctrl[:] = 1.0
    mujoco.mj_step(model, data, nstep=n_steps)
    return dict(qpos=float(np.max(np.abs(qpos - data.qpos))), qvel=float(np.max(np.abs(qvel - data.qvel))))


def horizon(case, settings):
    """MJX and MuJoCo C on ``case`` at ``settings`` (MuJoCo C ignores ``precision`` and ``device``): the largest
    differences over the horizon and the floors they are set against.

    Returns
    -------
    dict with ``orientation`` (rad, max over bodies and samples), ``position`` (m), ``floor`` (the case's
    double-precision orientation floor, rad, NaN where the case has none) and ``float32_floor`` (rad; NaN
    but for the torque-free top)
    """
    from dalembert import spatial
    from dalembert.adapters import get_adapter
    from dalembert.settings import Settings

    mjx_adapter, mj = get_adapter("mjx"), get_adapter("mujoco")
    a = mjx_adapter.run(mjx_adapter.prepare(case.scene, case.times, settings)).trajectory
    c_settings = Settings(settings.integrator, dt=settings.dt,
                          options={k: v for k, v in settings.options.items() if k not in ("precision", "device")})
    b = mj.run(mj.prepare(case.scene, case.times, c_settings)).trajectory
    orientation = max(float(np.max(spatial.rotation_angle(a.bodies[n].quaternion, b.bodies[n].quaternion)))
                      for n in a.bodies)
    position = max(float(np.max(np.abs(a.bodies[n].position - b.bodies[n].position))) for n in a.bodies)
    return dict(orientation=orientation, position=position,
                floor=float(case.floor().get("orientation", np.nan)),
                float32_floor=float32_floor(case.scene, case.times, settings.dt))


def float32_floor(scene, times, dt):
    """The float32 attitude floor (rad) of a torque-free top ``scene`` sampled at ``times`` (s) at step ``dt``:
    RK4 in float32 against the same RK4 in double; NaN for any other scene."""
    joints = scene.joints
    if len(joints) != 1 or joints[0].kind != "free" or scene.loads or any(scene.gravity):
        return float("nan")
    inertia = np.diag(scene.bodies[0].inertia_matrix)
    if np.any(np.abs(scene.bodies[0].inertia_matrix - np.diag(inertia)) > 0.0) or joints[0].q0[3:] != (1, 0, 0, 0):
        return float("nan")  # top_roundoff: principal axes, starting at the identity
    return _top_float32_floor(tuple(float(x) for x in inertia), tuple(float(w) for w in joints[0].v0[3:]),
                              tuple(float(t) for t in np.asarray(times)), float(dt))


@functools.lru_cache(maxsize=32)
def _top_float32_floor(inertia, w0, times, dt):
    """``top_roundoff`` in float32, once per top, sampling and step in a process: a worker audits each
    integrator's float32 run of a case version, and they share the floor (~1 s at dt 1e-3 over 20 s)."""
    from dalembert.reference.roundoff import top_roundoff

    return top_roundoff(inertia, w0, np.asarray(times), dt, working=np.float32, extended=float)
