"""Newton adapter: ``newton`` (NVIDIA, Google DeepMind, Disney Research; Warp kernels, float32) on Warp's CPU
backend, each rigid-body solver an integrator family.

Modules by job: ``engine`` (Warp initialized quietly on its kernel cache, Newton imported; the version),
``model`` (the scene as Newton's ``Model``: bodies, joints, the initial state; what it cannot hold), ``solvers``
(the families, their options and defaults, the settings read back), ``stepping`` (loads into ``body_f``, the
step loop, the samples), ``adapter`` (``NewtonAdapter``: the contract). Warp and Newton are imported only inside
functions.
"""

from dalembert.adapters.newton.adapter import NewtonAdapter

__all__ = ["NewtonAdapter"]
