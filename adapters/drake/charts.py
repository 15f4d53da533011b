"""Keeping Drake's ball joints clear of their singularity: ``BallCharts``.

Drake has no quaternion ball joint: a ball joint is a ``BallRpyJoint``, whose
coordinates are the roll-pitch-yaw angles of ``R_FM`` (``R = Rz(yaw) Ry(pitch)
Rx(roll)``) between its frame F on the parent and M on the child. Its rates are
singular at pitch = +-pi/2, where M's x axis lies along F's z axis, and Drake
stops the simulation there (``MapVelocityToQDot``). A top spinning about a
horizontal axis reaches that in a quarter turn (the heavy top of
``dalembert.cases.heavy_top``: 10 ms), so the joint's *chart* is moved, as a
differential-geometry code moves a chart on SO(3):

* the joint's frames become ``F' = F R_a`` and ``M' = M R_b`` (same origins),
  set in the simulator's context (``FixedOffsetFrame.SetPoseInParentFrame``:
  the frame poses are parameters, the plant is not rebuilt);
* a new chart puts ``R_F'M' = I`` (rpy = 0, a quarter turn from the singular
  set) with M's x axis along the joint's current angular velocity, so the spin
  is a roll, which never meets the singularity;
* the state is carried over exactly: ``R_F'M' = R_a^T R_FM R_b``,
  ``w_F'M'_F' = R_a^T w_FM_F`` (``BallRpyJoint``'s ``v`` is ``w_FM_F``).

A chart is set at t = 0 and again after any sample (error-controlled runs:
any step) at which ``|pitch|`` exceeds ``RECHART_PITCH``. Samples are always recorded in the scene's own
chart (F, M), so the read-back and the plant's default context never see a
moved frame. Between re-charts Drake integrates its own equations unchanged;
a re-chart is a change of coordinates between two steps, not a change of the
motion (to roundoff).
"""

from __future__ import annotations

import numpy as np

__all__ = ["BallCharts", "RECHART_PITCH"]

# rad: re-chart once |pitch| passes this at a sample. The singularity is at pi/2 = 1.571; the
# ~0.57 rad left is what one sample interval may turn the chart's x axis (the angular velocity's
# direction, not the spin about it) towards F's z axis: the Kovalevskaya top's ~5 rad/s tumble turns
# it by ~0.5 rad in its 0.1 s interval at most, a fast top's precession far less.
RECHART_PITCH = 1.0
# rad/s: below this angular speed the direction of the angular velocity says nothing; a new chart
# keeps the child side and only zeroes the angles.
STILL = 1e-9


def _rpy_to_matrix(rpy):
    from pydrake.math import RollPitchYaw

    return RollPitchYaw(np.asarray(rpy, dtype=float)).ToRotationMatrix().matrix()


def _matrix_to_rpy(R):
    from pydrake.math import RollPitchYaw, RotationMatrix

    return RollPitchYaw(RotationMatrix(R)).vector()


def _frame_with_x_along(u):
    """A rotation matrix (3, 3) whose first column is the unit vector ``u`` (3,)."""
    x = u / np.linalg.norm(u)
    helper = np.eye(3)[int(np.argmin(np.abs(x)))]  # the axis least aligned with x
    y = np.cross(x, helper)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


class BallCharts:
    """The charts of a model's ball joints during one simulation.

    Parameters
    ----------
    model : ``DrakeModel``
    plant_context : the plant's context inside the simulator's (the one the frames are set in)
    """

    def __init__(self, model, plant_context):
        self.plant, self.context = model.plant, plant_context
        self.balls = [model.joints[j.child] for j in model.scene.joints if j.kind == "ball"]
        # per joint: (R_a, R_b), the chart's rotations of F and M; the scene's own chart at first
        self.charts = [(np.eye(3), np.eye(3)) for _ in self.balls]
        self.X_PF = [joint.frame_on_parent().GetPoseInParentFrame(plant_context) for joint in self.balls]
        self.X_CM = [joint.frame_on_child().GetPoseInParentFrame(plant_context) for joint in self.balls]
        self.recharts = 0

    def __bool__(self):
        return bool(self.balls)

    def _slices(self, joint):
        nq = self.plant.num_positions()
        a, b = joint.position_start(), joint.velocity_start()
        return slice(a, a + 3), slice(nq + b, nq + b + 3)

    def to_scene_chart(self, x):
        """The state ``x`` (nq + nv,) of the current charts in the scene's chart (a copy)."""
        x = np.array(x, dtype=float)
        for joint, (R_a, R_b) in zip(self.balls, self.charts):
            sq, sv = self._slices(joint)
            x[sq] = _matrix_to_rpy(R_a @ _rpy_to_matrix(x[sq]) @ R_b.T)
            x[sv] = R_a @ x[sv]
        return x

    def due(self, positions):
        """Whether a ball joint's ``|pitch|`` exceeds ``RECHART_PITCH`` in the plant's ``positions (nq,)``: ``update``
        would move its chart."""
        return any(abs(positions[joint.position_start() + 1]) > RECHART_PITCH for joint in self.balls)

    def update(self, force=False):
        """Re-chart every ball joint whose ``|pitch|`` exceeds ``RECHART_PITCH`` (every one if ``force``),
        carrying the context's state over; the number of joints re-charted."""
        if not self.balls:  # (called after every sample)
            return 0
        x = self.plant.GetPositionsAndVelocities(self.context)
        moved = 0
        for i, joint in enumerate(self.balls):
            sq, sv = self._slices(joint)
            if not force and abs(x[sq][1]) <= RECHART_PITCH:
                continue
            R_a, R_b = self.charts[i]
            R_FM = R_a @ _rpy_to_matrix(x[sq]) @ R_b.T  # the scene's chart
            w_F = R_a @ x[sv]
            w_M = R_FM.T @ w_F
            with np.errstate(over="ignore", invalid="ignore"):
                speed = np.linalg.norm(w_M)
            if not np.isfinite(speed):  # a blow-up under way: no chart helps, and Drake reports it as data
                continue
            R_b = _frame_with_x_along(w_M) if speed > STILL else R_b
            R_a = R_FM @ R_b  # so that R_F'M' = R_a^T R_FM R_b = I
            self._set_frames(i, joint, R_a, R_b)
            x[sq], x[sv] = 0.0, R_a.T @ w_F
            self.charts[i] = (R_a, R_b)
            moved += 1
        if moved:
            self.plant.SetPositionsAndVelocities(self.context, x)
            self.recharts += moved
        return moved

    def _set_frames(self, i, joint, R_a, R_b):
        from pydrake.math import RigidTransform, RotationMatrix

        X_PF = self.X_PF[i] @ RigidTransform(RotationMatrix(R_a), np.zeros(3))
        X_CM = self.X_CM[i] @ RigidTransform(RotationMatrix(R_b), np.zeros(3))
        joint.frame_on_parent().SetPoseInParentFrame(self.context, X_PF)
        joint.frame_on_child().SetPoseInParentFrame(self.context, X_CM)
