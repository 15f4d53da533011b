"""Robots from model files: URDF and MJCF into a ``Scene`` (a layer beside the scene; it imports the core only).

``read_urdf`` / ``read_mjcf`` return an ``ImportedModel``: the scene (bodies at their COMs with rotated
inertias, the joint tree), ``FileEffects`` (what the file calls for beyond bodies and joints, left out) and
the file's joint names. ``robot_path`` finds a named robot of the ``example-robot-data`` package.
"""

from dalembert.models.library import ROBOTS, robot_path
from dalembert.models.mjcf import read_mjcf
from dalembert.models.tree import FileEffect, FileEffects, ImportedModel, ModelError
from dalembert.models.urdf import read_urdf

__all__ = ["read_urdf", "read_mjcf", "robot_path", "ROBOTS", "ImportedModel", "FileEffects", "FileEffect",
           "ModelError"]
