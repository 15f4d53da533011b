"""When a trajectory stops being finite: every sampled array counts, not only the bodies' states.

An engine can blow up in its joint coordinates (or a reported reaction) while the bodies it reads
back stay finite for a sample; the harness then stores the run as diverged at that sample, and must
never fail to say when (a run whose only non-finite numbers were joint coordinates crashed the
harness with a ``TypeError`` on formatting ``None``).
"""

import dataclasses

import numpy as np

from dalembert import make_case
from dalembert.trajectory import JointStates


def _pendulum():
    case = make_case("pendulum")
    traj = case.exact(case.times)
    assert traj.joints and traj.is_finite()  # the truth samples its joint coordinates
    return traj


def test_finite_trajectory_has_no_divergence_time():
    assert _pendulum().first_nonfinite_time() is None


def test_a_joint_coordinate_alone_gives_the_divergence_time():
    traj = _pendulum()
    k = len(traj.t) // 3
    name, j = next(iter(traj.joints.items()))
    q = j.q.copy()
    q[k:] = np.nan
    bad = dataclasses.replace(traj, joints={**traj.joints, name: JointStates(q, j.v)})
    assert not bad.is_finite()
    assert bad.first_nonfinite_time() == traj.t[k]


def test_an_extra_series_alone_gives_the_divergence_time():
    traj = _pendulum()
    k = len(traj.t) - 2
    reaction = np.zeros((len(traj.t), 3))
    reaction[k, 1] = np.inf
    bad = dataclasses.replace(traj, extras={**traj.extras, "reaction_force:hinge": reaction})
    assert bad.first_nonfinite_time() == traj.t[k]
