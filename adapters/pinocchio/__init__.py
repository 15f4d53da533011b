"""Pinocchio adapter: the scene through Pinocchio's dynamics, with the integrators owned here.

Modules by job: ``model`` (``PinocchioModel``: the scene as a ``pin.Model``,
its loads, accelerations and ``dexp^-1``), ``loops`` (loop closures as rigid
constraints for ``pin.constraintDynamics``: placement, regularisation, drift
correction, reactions), ``integrators`` (the fixed-step and
adaptive loops in Python), ``native`` (the fixed-step loop compiled from
``stepper.cpp``; ``python -m dalembert.adapters.pinocchio.native`` builds it),
``readback`` (the sampled states in body terms, joint and loop reactions),
``audit`` (what the run simulated, read back from the model), ``contact``
(the contact time-stepper: the scene's pairs detected each step, one cone problem solved by pin's ADMM
or PGS, semi-implicit Euler with impulses), ``adapter`` (``PinocchioAdapter``).
"""

from dalembert.adapters.pinocchio.adapter import PinocchioAdapter

__all__ = ["PinocchioAdapter"]
