"""tinyrigid: a rigid-body engine in numpy (``engine``) and its dalembert adapter (``adapter``).

The worked example of dalembert's engine guide (docs/engines.md): an engine written from scratch, with the
conventions of the engines one meets in practice (quaternions scalar last, angular velocity in world axes,
velocity damping and joint motors an engine may add by default), and an adapter that maps dalembert's scenes
onto it and its results back.
"""

__version__ = "0.1.0"
