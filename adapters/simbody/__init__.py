"""Simbody adapter, through OpenSim 4.6 (``opensim``): the scene as an OpenSim model on Simbody's reduced
coordinates, exactly the scene's physics.

Modules by job: ``model`` (the model, its frames and charts, OpenSim's coordinate defaults switched off, the
silent import), ``stepping`` (OpenSim's ``Manager`` with each of Simbody's integrators, from sample to sample),
``readback`` (Simbody's states in body terms, the joints' reactions), ``audit`` (what the run simulated, read
back from the model), ``adapter`` (``SimbodyAdapter``). OpenSim itself is imported only inside functions.
"""

from dalembert.adapters.simbody.adapter import SimbodyAdapter

__all__ = ["SimbodyAdapter"]
