"""MuJoCo adapter: the scene as generated MJCF, exactly the scene's physics.

Modules by job: ``mjcf`` (the model as MJCF text and where the scene's body
frames sit in MuJoCo's; importable without MuJoCo), ``stepping`` (``rollout`` in
chunks, divergence, the ``xfrc_applied`` load path), ``readback`` (MuJoCo's
states in body terms, joint reactions), ``audit`` (what the run simulated, read
back from the compiled model), ``adapter`` (``MujocoAdapter``).
"""

from dalembert.adapters.mujoco.adapter import MujocoAdapter
from dalembert.adapters.mujoco.mjcf import mjcf

__all__ = ["MujocoAdapter", "mjcf"]
