"""dalembert: a validation harness for multibody physics engines."""

from dalembert.case import Case, Tolerance, case, load_cases, make_case
from dalembert.result import Cost, RunResult
from dalembert.scene import Body, Joint, Load, Scene, SceneError
from dalembert.settings import Settings
from dalembert.trajectory import BodyStates, JointStates, Trajectory

__version__ = "0.1.0"

__all__ = [
    "Body", "BodyStates", "Case", "Cost", "Joint", "JointStates", "Load", "RunResult", "Scene", "SceneError",
    "Settings", "Tolerance", "Trajectory", "case", "load_cases", "make_case", "__version__",
]
