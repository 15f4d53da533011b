"""Closed-form solutions, one module each, each citing its source."""

from dalembert.reference.closed_form.ball_slide_to_roll import SlidingBall
from dalembert.reference.closed_form.ballistic import Ballistic
from dalembert.reference.closed_form.block_on_incline import SlidingBlock
from dalembert.reference.closed_form.bouncing_ball import BouncingBall
from dalembert.reference.closed_form.free_top import TorqueFreeTop
from dalembert.reference.closed_form.heavy_top import LagrangeTop
from dalembert.reference.closed_form.normal_modes import NormalModes, rod_chain_matrices
from dalembert.reference.closed_form.pendulum import RigidPendulum
from dalembert.reference.closed_form.pivoted_rod import FollowerForceRod
from dalembert.reference.closed_form.rolling_ball import RollingBall
from dalembert.reference.closed_form.sphere_collision import HeadOnCollision

__all__ = ["Ballistic", "BouncingBall", "FollowerForceRod", "HeadOnCollision", "LagrangeTop", "NormalModes",
           "RigidPendulum", "RollingBall", "SlidingBall", "SlidingBlock", "TorqueFreeTop", "rod_chain_matrices"]
