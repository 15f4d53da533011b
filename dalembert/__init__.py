"""dalembert: a validation harness for multibody physics engines.

This package is the core (scene, spatial, case, settings, trajectory, invariants,
errors, judge, record, store, registry, stepping); it imports nothing from the
packages built on it: ``dalembert.reference``, ``dalembert.cases``,
``dalembert.adapters``, ``dalembert.reports`` and ``dalembert.harness``, which joins them.
"""

from dalembert.case import Case, CaseRecord, Tolerance, case, load_cases, make_case
from dalembert.record import Cost, RunRecord
from dalembert.scene import Body, Joint, Load, Scene, SceneError
from dalembert.settings import Settings
from dalembert.trajectory import BodyStates, JointStates, Trajectory

__version__ = "0.1.0"

__all__ = [
    "Body", "BodyStates", "Case", "CaseRecord", "Cost", "Joint", "JointStates", "Load", "RunRecord", "Scene",
    "SceneError", "Settings", "Tolerance", "Trajectory", "case", "load_cases", "make_case", "__version__",
]
