"""Exudyn adapter: free bodies on rigid-body nodes, jointed trees in minimal or redundant
coordinates, with Exudyn's own solvers.

Modules by job: ``model`` (``build``: the scene as an Exudyn system), ``joints`` (the
scene's joints in Exudyn's terms, and read back from the built system), ``sampling``
(the solve sampled at the case's times, through Exudyn's stored sensors or from
Python, and the guards that stop a stuck adaptive solve), ``readback`` (the
sampled sensors in body terms, joint and loop reactions), ``audit`` (what the
run simulated, read back from the system), ``adapter`` (``ExudynAdapter``:
solvers, options).
"""

from dalembert.adapters.exudyn.adapter import ExudynAdapter

__all__ = ["ExudynAdapter"]
