"""Resultant of a scene's loads and gravity on one body (shared by the formulations)."""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["BodyLoads", "TreeLoads"]


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


class TreeLoads:
    """``BodyLoads`` of every body of a tree at once: the resultants of all bodies from their rotations stacked.

    Parameters
    ----------
    scene : Scene
    bodies : sequence of Body — in the order of the rotations ``resultant`` is given
    """

    def __init__(self, scene, bodies):
        each = [BodyLoads(scene, body) for body in bodies]
        n = len(each)
        self.F_W = np.array([b.F_W for b in each]).reshape(n, 3)
        self.gravity_force_W = (np.array([b.gravity_force_W for b in each]).reshape(n, 3)
                                if each and each[0].gravity_force_W is not None else None)
        self.tau_W = np.array([b.tau_W for b in each]).reshape(n, 3)
        # the body-frame terms only where a body has one (a product with zeros would add nothing)
        self.F_B = np.array([b.F_B for b in each]).reshape(n, 3) if any(np.any(b.F_B) for b in each) else None
        self.tau_B = np.array([b.tau_B for b in each]).reshape(n, 3) if any(np.any(b.tau_B) for b in each) else None
        self.world_point_forces = [(i, p_B, F_W) for i, b in enumerate(each) for p_B, F_W in b.world_point_forces]
        # without body-frame forces, the force is a constant: BodyLoads' F_W + gravity, summed once
        self._F = self.F_W if self.gravity_force_W is None else self.F_W + self.gravity_force_W

    def resultant(self, R_WB):
        """Force (N) and moment about the COM (N m) on each body, world axes, shape (..., n, 3) each, new arrays,
        from the bodies' rotations ``R_WB`` (..., n, 3, 3): ``BodyLoads.resultant`` of each."""
        if self.F_B is None:
            F = self._F
        else:
            F = self.F_W + (R_WB @ self.F_B[:, :, None])[..., 0]
            if self.gravity_force_W is not None:
                F = F + self.gravity_force_W
        tau = self.tau_W if self.tau_B is None else (R_WB @ self.tau_B[:, :, None])[..., 0] + self.tau_W
        shape = R_WB.shape[:-1]  # (new arrays: the springs' wrenches are added in place)
        F = (F.copy() if F is self._F and F.shape == shape else F if F.shape == shape
             else np.broadcast_to(F, shape).copy())
        tau = (tau.copy() if tau is self.tau_W and tau.shape == shape else tau if tau.shape == shape
               else np.broadcast_to(tau, shape).copy())
        for i, p_B, F_W in self.world_point_forces:
            tau[..., i, :] += spatial.cross(R_WB[..., i, :, :] @ p_B, F_W)
        return F, tau
