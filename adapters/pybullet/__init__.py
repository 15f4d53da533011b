"""PyBullet adapter: the scene as PyBullet multibodies (reduced coordinates), exactly the scene's physics.

Modules by job: ``model`` (the multibodies, the frames, PyBullet's defaults switched off, the silent
import), ``contact`` (free bodies' geoms, planes and the named pairs as PyBullet's hard contact), ``stepping``
(``stepSimulation`` step by step, the loads applied before each), ``readback``
(PyBullet's states in body terms, the joint sensors' reactions), ``audit`` (what the run simulated, read
back from the engine, and the probe of what it does not report), ``adapter`` (``PybulletAdapter``).
PyBullet itself is imported only inside functions.
"""

from dalembert.adapters.pybullet.adapter import PybulletAdapter

__all__ = ["PybulletAdapter"]
