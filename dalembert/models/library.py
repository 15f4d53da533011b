"""The robots of the ``example-robot-data`` package (Pinocchio's benchmark set), by name.

The package (``pip install dalembert[robots]``) installs its URDFs under its ``cmeel.prefix`` data folder;
they are found through the package's own file list (``importlib.metadata``), with no network.
"""

from __future__ import annotations

import importlib.metadata
import os

from dalembert.models.tree import ModelError

__all__ = ["ROBOTS", "DISTRIBUTION", "robot_path", "robot_files"]

DISTRIBUTION = "example-robot-data"
# Short names -> the URDF's path inside the package's data folder.
ROBOTS = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
}
_DATA = "cmeel.prefix/share/example-robot-data/robots"


def _robots_folder(name):
    try:
        dist = importlib.metadata.distribution(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        raise ModelError(f"robot.model: {name!r} comes from {DISTRIBUTION}, not installed — pip install "
                         "dalembert[robots]", "not installed") from None
    return str(dist.locate_file(_DATA))


def robot_files():
    """Every URDF the package installs: sorted absolute paths."""
    folder = _robots_folder("every robot")
    out = []
    for here, _dirs, files in os.walk(folder):
        out += [os.path.join(here, f) for f in files if f.endswith(".urdf")]
    return sorted(out)


def robot_path(model):
    """The file of ``model``: a name of ``ROBOTS`` or a path to a .urdf / .xml file of the user's own."""
    if model in ROBOTS:
        return os.path.join(_robots_folder(model), ROBOTS[model])
    if os.path.isfile(model):
        return model
    raise ModelError(f"robot.model: {model!r} is neither a known robot ({', '.join(ROBOTS)}) nor a file — give one "
                     "of those names or the path of a .urdf or MJCF .xml file", "unknown model")
