"""MJX adapter: MuJoCo XLA (``mujoco.mjx``, JAX) on the MuJoCo adapter's model.

Modules by job: ``stepping`` (the compiled rollout, precision switching, the
quiet import of MJX), ``adapter`` (``MjxAdapter``: the MuJoCo adapter's model
and read-back around MJX's stepping), ``parity`` (MJX against MuJoCo C at the
same settings: one step and the horizon, against the roundoff floors). JAX and
MJX are imported only inside functions.
"""

from dalembert.adapters.mjx.adapter import MjxAdapter

__all__ = ["MjxAdapter"]
