"""Closed-form solutions, one module each, each citing its source."""

from dalembert.reference.closed_form.ballistic import Ballistic
from dalembert.reference.closed_form.free_top import TorqueFreeTop
from dalembert.reference.closed_form.pivoted_rod import FollowerForceRod

__all__ = ["Ballistic", "FollowerForceRod", "TorqueFreeTop"]
