"""MuJoCo Warp against MuJoCo C at the same settings: a few steps, and over a horizon.

``one_step`` steps both engines from the same initial state of the same compiled
model and returns the largest differences in ``qpos`` and ``qvel``; ``horizon``
runs both adapters on a case and returns the largest differences between the two
trajectories (orientation as the geodesic angle, rad; COM position, m) beside the
floors they are set against: the case's double-precision floor and, for a
torque-free top, the float32 floor (``dalembert.adapters.mjx.parity.float32_floor``:
RK4 in float32 against the same RK4 in double). MuJoCo Warp computes in float32,
so a difference near the float32 floor is its number type; one far above it is a
different computation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["one_step", "horizon"]


def one_step(case, settings, n_steps=1):
    """Largest ``|qpos_Warp - qpos_C|`` and ``|qvel_Warp - qvel_C|`` after ``n_steps`` steps from the case's
    initial state: ``dict(qpos=..., qvel=...)`` (the engine's units: m, rad, quaternion components, m/s, rad/s).
    MuJoCo Warp steps through the adapter's prepared model (the program a run of the case executes)."""
    import mujoco

    from dalembert.adapters import get_adapter
    from dalembert.adapters.mujoco_warp.stepping import put_state, step_samples

    times = np.asarray(case.times[:1], dtype=float)
    p = get_adapter("mujoco_warp").prepare(case.scene, np.append(times, times[0] + n_steps * settings.dt), settings)
    d = put_state(p.model, p.qpos0, p.qvel0, p.ctrl, device=p.device)  # on the device option ``device`` names
    Q, V, _, _ = step_samples(p.mx, d, [n_steps], p.qpos0, p.qvel0)
    model, data = p.model, mujoco.MjData(p.model)
    data.qpos[:], data.qvel[:] = p.qpos0, p.qvel0
    if p.ctrl is not None:
        data.ctrl[:] = p.ctrl
    mujoco.mj_step(model, data, nstep=n_steps)
    return dict(qpos=float(np.max(np.abs(Q[1] - data.qpos))), qvel=float(np.max(np.abs(V[1] - data.qvel))))


def horizon(case, settings, times=None):
    """MuJoCo Warp and MuJoCo C on ``case`` at ``settings``, sampled at ``times`` (s; default the case's): the
    largest differences and the floors they are set against.

    Returns
    -------
    dict with ``orientation`` (rad, max over bodies and samples), ``position`` (m), ``floor`` (the case's
    double-precision orientation floor, rad, NaN where the case has none) and ``float32_floor`` (rad; NaN
    but for the torque-free top)
    """
    from dalembert import spatial
    from dalembert.adapters import get_adapter
    from dalembert.adapters.mjx.parity import float32_floor
    from dalembert.settings import Settings

    whole = times is None  # the case's floor is for its own horizon
    times = np.asarray(case.times if whole else times, dtype=float)
    warp_adapter, mj = get_adapter("mujoco_warp"), get_adapter("mujoco")
    a = warp_adapter.run(warp_adapter.prepare(case.scene, times, settings)).trajectory
    c_settings = Settings(settings.integrator, dt=settings.dt,  # MuJoCo C runs on the host: no ``device``
                          options={k: v for k, v in settings.options.items() if k != "device"})
    b = mj.run(mj.prepare(case.scene, times, c_settings)).trajectory
    with np.errstate(invalid="ignore"):
        orientation = max(float(np.max(spatial.rotation_angle(a.bodies[n].quaternion, b.bodies[n].quaternion)))
                          for n in a.bodies)
        position = max(float(np.max(np.abs(a.bodies[n].position - b.bodies[n].position))) for n in a.bodies)
    return dict(orientation=orientation, position=position,
                floor=float(case.floor().get("orientation", np.nan)) if whole else float("nan"),
                float32_floor=float32_floor(case.scene, times, settings.dt))
