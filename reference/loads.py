"""Resultant of a scene's loads and gravity on one body (shared by the formulations)."""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["BodyLoads"]


class BodyLoads:
    """The constant loads on one body, split by frame for fast evaluation.

    Parameters
    ----------
    scene : Scene
    body : Body
    """

    def __init__(self, scene, body):
        ls = [ld for ld in scene.loads if ld.body == body.name]
        g = np.array(scene.gravity)
        self.gravity_force_W = body.mass * g if np.any(g) else None  # only the terms the scene has
        self.F_W = sum((np.array(ld.vector) for ld in ls if ld.kind == "force" and ld.frame == "world"), np.zeros(3))
        self.F_B = sum((np.array(ld.vector) for ld in ls if ld.kind == "force" and ld.frame == "body"), np.zeros(3))
        # Moments about the COM of point forces: body-frame ones are constant in B;
        # world-frame ones need the current attitude (kept as (point_B, F_W) pairs).
        self.tau_B = sum((spatial.cross(ld.point, ld.vector) for ld in ls if ld.kind == "force" and ld.frame == "body"),
                         np.zeros(3))
        self.tau_B += sum((np.array(ld.vector) for ld in ls if ld.kind == "torque" and ld.frame == "body"),
                          np.zeros(3))
        self.tau_W = sum((np.array(ld.vector) for ld in ls if ld.kind == "torque" and ld.frame == "world"),
                         np.zeros(3))
        self.world_point_forces = [(np.array(ld.point), np.array(ld.vector)) for ld in ls
                                   if ld.kind == "force" and ld.frame == "world" and any(ld.point)]

    def resultant(self, R_WB):
        """Force (N) and moment about the COM (N m), both in world axes, shape (3,) each."""
        F = self.F_W + R_WB @ self.F_B
        if self.gravity_force_W is not None:
            F = F + self.gravity_force_W
        tau = R_WB @ self.tau_B + self.tau_W
        for p_B, F_W in self.world_point_forces:
            tau = tau + spatial.cross(R_WB @ p_B, F_W)
        return F, tau
