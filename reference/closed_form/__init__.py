"""Closed-form solutions, one module each, each citing its source."""

from reference.closed_form.ballistic import Ballistic
from reference.closed_form.free_top import TorqueFreeTop
from reference.closed_form.pivoted_rod import FollowerForceRod

__all__ = ["Ballistic", "FollowerForceRod", "TorqueFreeTop"]
