"""MuJoCo Warp adapter: ``mujoco_warp`` (Warp kernels, float32) on the MuJoCo adapter's model, Warp's CPU backend.

Modules by job: ``stepping`` (Warp initialized on its kernel cache, the model and
state put on the device, ``mjw.step`` per step), ``adapter``
(``MujocoWarpAdapter``: the MuJoCo adapter's model, read-back and audit around
MuJoCo Warp's stepping), ``parity`` (MuJoCo Warp against MuJoCo C at the same
settings). Warp and MuJoCo Warp are imported only inside functions.
"""

from dalembert.adapters.mujoco_warp.adapter import MujocoWarpAdapter

__all__ = ["MujocoWarpAdapter"]
