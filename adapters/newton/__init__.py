"""Newton adapter: ``newton`` (NVIDIA, Google DeepMind, Disney Research; Warp kernels, float32) on Warp's CPU
backend, each rigid-body solver an integrator family.

Modules by job: ``engine`` (Warp initialized quietly on its kernel cache, Newton imported; the version),
``model`` (the scene as Newton's ``Model``: bodies, joints, the initial state, one world or a batch's; what it
cannot hold), ``solvers`` (the families, their options and defaults, the settings read back), ``mujoco_solver``
(Newton's MuJoCo solver's families, run in an engine environment of their own, and why they cannot run
elsewhere), ``stepping`` (loads into ``body_f``, the step loop, the samples), ``adapter`` (``NewtonAdapter``: the
contract and batches). Warp and Newton are imported only inside functions.
"""

from dalembert.adapters.newton.adapter import NewtonAdapter

__all__ = ["NewtonAdapter"]
