"""Drake adapter: the scene as a ``MultibodyPlant``, exactly the scene's physics.

Modules by job: ``model`` (the plant and its diagram, Drake's coordinates,
the audit read back from the plant), ``loads`` (the loads system that turns
follower forces with the body's pose), ``stepping`` (a ``Simulator`` from
sample to sample: Drake's integrators, fixed-step or error-controlled, or the
plant's discrete update), ``loops`` (loop closures as SAP constraints of the
discrete plant), ``springs`` (spring-dampers as ``LinearSpringDamper``
force elements, and their read-back for the audit), ``readback`` (Drake's states in body terms, joint reactions),
``audit`` (what the run simulated, read back from the plant), ``adapter`` (``DrakeAdapter``). Drake itself is imported only
inside functions.
"""

from dalembert.adapters.drake.adapter import DrakeAdapter

__all__ = ["DrakeAdapter"]
