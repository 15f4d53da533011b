"""DART adapter: the scene as a ``Skeleton`` in a DART ``World``, exactly the scene's physics.

Modules by job: ``model`` (the world and skeleton, DART's coordinates, what is switched off), ``stepping``
(``World.step`` from sample to sample, the loads), ``readback`` (DART's states in body terms, joint reactions),
``audit`` (what the run simulated, read back from the world), ``loops`` (ball and revolute loop closures as
DART's joint constraints), ``contact`` (one contact pair as DART's hard contact), ``adapter`` (``DartAdapter``). DART itself is
imported only inside functions.
"""

from dalembert.adapters.dart.adapter import DartAdapter

__all__ = ["DartAdapter"]
