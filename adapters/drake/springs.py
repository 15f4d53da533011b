"""Spring-dampers (``Scene.springs``) as Drake ``LinearSpringDamper`` force elements, and their read-back.

Each scene spring becomes one ``LinearSpringDamper(bodyA, p_AP, bodyB, p_BQ, free_length, stiffness,
damping)``: body a and its point as A and P, body b and its point as Q on B (Drake's body frames are the
scene's body frames, ``model``, so the points go in as they are; the world is Drake's world body), the rest
length as the free length. Drake's element applies ``f_AP = (k (l - l0) + c l') r`` on A at P, ``r`` the unit
vector P -> Q, and its opposite on B at Q (Drake's documentation of ``LinearSpringDamper``): the scene's
tension along the same line, ``+s e`` on a and ``-s e`` on b (``dalembert.springs``), in both modes.

What Drake cannot represent (``refusal``):

* a rest length of zero: Drake's constructor fails ("condition 'free_length > 0' failed", raised by pydrake as
  ``SystemExit``; Drake's documentation: "Since this force element is meant to model finite length springs,
  l0 must be strictly positive"; its length is the soft norm ``sqrt(l^2 + (eps l0)^2)``, which
  needs ``l0 > 0``). A zero-length spring is refused with that reason rather than given a small free length,
  which would be a different spring.

Drake also raises, while stepping, when the points come within ``eps l0`` (2.2e-16 l0) of each other ("the
length of the spring became nearly zero"); the run then fails with Drake's message (``stepping``). Its soft
norm changes the length by ``(eps l0)^2 / (2 l)``, ~1e-32 relative: not measurable.

How each mode steps it (measured, ``tests/test_drake_springs.py``):

* continuous mode: a force of the state, evaluated at every stage of Drake's integrator, like gravity; each
  scheme keeps its order (RK3 and Radau3 8-fold per halving, RK5 ~32-fold on the oscillators);
* discrete mode: EXPLICIT, damper included. The plant's update is semi-implicit (symplectic) Euler,
  ``v1 = v0 + dt M^-1 tau(q0, v0)``, then ``q1`` from ``v1``, and the spring-damper's force is taken at the
  step's start ``(q0, v0)``: SAP treats joint damping implicitly, not this element's damper (one step of a
  2-kg box on a c = 2000 N s/m damper at dt = 1e-2 gives the explicit 4.575 m/s from -0.5 m/s, where the
  implicit damper would give -0.039 m/s). So the damper adds no implicit smoothing and no implicit error: its
  error is explicit Euler's, first order like the rest of the update, and it is stable only while
  ``dt c / m_eff < 2``. On an undamped oscillator of amplitude ``a`` the update keeps the energy bounded (a
  tilted invariant ellipse) and lags in phase by ``omega^3 dt^2 t / 24``; its position error is led by the
  phase offset ``a omega dt / 2`` it starts with: first order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.scene import WORLD

__all__ = ["ZERO_REST_REASON", "SpringElement", "add_springs", "refusal", "read_springs", "passive_elements"]

ZERO_REST_REASON = ("Drake's LinearSpringDamper takes only a strictly positive free length (its constructor fails on "
                    "'free_length > 0': the element models pre-loaded finite-length springs); a spring of rest length "
                    "0 cannot be built")


@dataclass(frozen=True)
class SpringElement:
    """One scene spring and the Drake force element built for it: ``spring`` (``Spring``), ``element``
    (``LinearSpringDamper``)."""

    spring: object
    element: object


def refusal(scene):
    """The reason Drake cannot build the springs of ``scene`` (``ZERO_REST_REASON`` with their names), or None."""
    zero = [sp.name for sp in scene.springs if sp.rest_length == 0.0]
    if zero:
        return f"springs {', '.join(repr(n) for n in zero)} (rest length 0): {ZERO_REST_REASON}"
    return None


def add_springs(plant, scene, bodies):
    """Add every spring of ``scene`` to ``plant`` (not finalized; ``bodies``: name -> ``RigidBody``) as a
    ``LinearSpringDamper``; a ``SpringElement`` per spring, in the scene's order."""
    from pydrake.multibody.tree import LinearSpringDamper

    side = lambda name: plant.world_body() if name == WORLD else bodies[name]  # noqa: E731
    out = []
    for sp in scene.springs:
        element = plant.AddForceElement(LinearSpringDamper(
            side(sp.body_a), np.asarray(sp.point_a, dtype=float), side(sp.body_b), np.asarray(sp.point_b, dtype=float),
            sp.rest_length, sp.stiffness, sp.damping))
        out.append(SpringElement(sp, element))
    return out


def _body_name(plant, body):
    """The scene's name of a Drake body: ``"world"`` for Drake's world body."""
    return WORLD if body.index() == plant.world_body().index() else body.name()


def read_springs(plant):
    """Every ``LinearSpringDamper`` of the finalized ``plant``, read back from the plant itself: a list of dicts
    ``body_a``, ``point_a`` (m, A's frame), ``body_b``, ``point_b`` (m, B's frame), ``rest_length`` (m),
    ``stiffness`` (N/m), ``damping`` (N s/m), in the order of Drake's force elements."""
    from pydrake.multibody.tree import ForceElementIndex, LinearSpringDamper

    out = []
    for i in range(plant.num_force_elements()):
        fe = plant.get_force_element(ForceElementIndex(i))
        if isinstance(fe, LinearSpringDamper):
            out.append(dict(body_a=_body_name(plant, fe.bodyA()), point_a=tuple(float(x) for x in fe.p_AP()),
                            body_b=_body_name(plant, fe.bodyB()), point_b=tuple(float(x) for x in fe.p_BQ()),
                            rest_length=float(fe.free_length()), stiffness=float(fe.stiffness()),
                            damping=float(fe.damping())))
    return out


def passive_elements(plant):
    """The type names of the plant's force elements that are neither its gravity field nor a
    ``LinearSpringDamper`` (joint springs, bushings, dampers a model could carry): empty for a scene's plant."""
    from pydrake.multibody.tree import ForceElementIndex, LinearSpringDamper, UniformGravityFieldElement

    return [type(fe).__name__ for fe in (plant.get_force_element(ForceElementIndex(i))
                                         for i in range(plant.num_force_elements()))
            if not isinstance(fe, (UniformGravityFieldElement, LinearSpringDamper))]
