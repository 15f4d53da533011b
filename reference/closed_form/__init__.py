"""Closed-form solutions, one module each, each citing its source."""

from dalembert.reference.closed_form.ballistic import Ballistic
from dalembert.reference.closed_form.free_top import TorqueFreeTop
from dalembert.reference.closed_form.heavy_top import LagrangeTop
from dalembert.reference.closed_form.normal_modes import NormalModes, rod_chain_matrices
from dalembert.reference.closed_form.pendulum import RigidPendulum
from dalembert.reference.closed_form.pivoted_rod import FollowerForceRod

__all__ = ["Ballistic", "FollowerForceRod", "LagrangeTop", "NormalModes", "RigidPendulum", "TorqueFreeTop",
           "rod_chain_matrices"]
