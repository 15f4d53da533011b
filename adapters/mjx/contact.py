"""MJX's contact forces, its own: per sample, ``mjx.forward`` at the sample's state (all samples at once, vmapped),
and from its ``Data`` each contact's constraint force ``efc_force`` decoded into the contact frame as MuJoCo's
``mj_contactForce`` does (MuJoCo's engine_support.c: an elliptic cone's rows are the normal and tangential forces
themselves; a pyramidal cone's 2 (dim - 1) facet forces f give the normal ``sum f`` and the tangent j ``(f[2j] -
f[2j+1]) mu_j``), turned into world axes with the contact frame (rows: normal, tangents; the force geom[0] exerts on
geom[1]) and summed per scene pair ON the pair's subject (``dalembert.contact.subject``), as MuJoCo's read-back
does (``mujoco.contact.force_reader``). MJX keeps a fixed set of candidate contacts: one not touching has zero
force. It is the force of the step that starts at the sample's state, from MJX's own solver (not MuJoCo C's)."""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["read_forces"]


@functools.cache
def _forward_contacts():
    """The compiled ``(m, d, Q, V) -> (geom, frame, dim, efc_address, friction, efc_force)`` over the samples.
    Built once per process, as ``stepping``'s rollout is: JAX keys its compilations by the function, so a new one per
    call traced, lowered and compiled again for a model and sample count already seen (5-9 s a compile on 2 cores)."""
    import jax

    from dalembert.adapters.mjx.stepping import mjx

    module = mjx()

    def one(m, d, q, v):
        out = module.forward(m, d.replace(qpos=q, qvel=v))
        c = out._impl.contact
        return c.geom, c.frame, c.dim, c.efc_address, c.friction, out._impl.efc_force

    return jax.jit(jax.vmap(one, in_axes=(None, None, 0, 0)))


def read_forces(p, Q, V):
    """The contact force (N, world) ON each of the scene's pairs' subjects at MJX's sampled states ``Q (n, nq)``,
    ``V (n, nv)`` (host float64), ndarray (n, n_pairs, 3), NaN where a state is not finite; None without contact.
    ``p``: the ``MjxPrepared`` (its device model ``mx``, initial data ``dx0``, precision and MuJoCo C model)."""
    import mujoco

    from dalembert.adapters.mjx.adapter import _padded
    from dalembert.adapters.mjx.stepping import precision
    from dalembert.contact import subject

    scene = p.scene
    if not scene.contacts:
        return None
    gid = lambda name: mujoco.mj_name2id(p.model, mujoco.mjtObj.mjOBJ_GEOM, name)  # noqa: E731
    index = {frozenset((gid(c.a), gid(c.b))): (i, gid(subject(scene, c))) for i, c in enumerate(scene.contacts)}
    pyramidal = p.model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    out = np.full((len(Q), len(scene.contacts), 3), np.nan)
    finite = np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
    if len(finite) == 0:
        return out
    dtype = np.float64 if p.precision == "float64" else np.float32
    # the finite samples padded with copies of the last to a power of two, as the worlds are (``adapter._padded``):
    # JAX compiles once per sample count, and runs of other horizons or steps, or that diverged part way, share one
    take = np.concatenate([finite, np.full(_padded(len(finite)) - len(finite), finite[-1])])
    with precision(p.precision):
        found = _forward_contacts()(p.mx, p.dx0, Q[take].astype(dtype), V[take].astype(dtype))
    geom, frame, dim, adr, friction, efc = (np.asarray(a, dtype=float) if i in (1, 4, 5) else np.asarray(a)
                                            for i, a in enumerate(found))
    for row, k in enumerate(finite):
        total = np.zeros((len(scene.contacts), 3))
        for c in range(geom.shape[1]):
            g0, g1 = int(geom[row, c, 0]), int(geom[row, c, 1])
            hit = index.get(frozenset((g0, g1)))
            a, n = int(adr[row, c]), int(dim[row, c])
            if hit is None or a < 0:
                continue
            f = np.zeros(3)
            if n == 1 or not pyramidal:
                f[:min(n, 3)] = efc[row, a:a + min(n, 3)]
            else:
                facets = efc[row, a:a + 2 * (n - 1)]
                f[0] = facets.sum()
                mu = friction[row, c]
                for j in range(min(n - 1, 2)):
                    f[j + 1] = (facets[2 * j] - facets[2 * j + 1]) * mu[j]
            f_W = frame[row, c].reshape(3, 3).T @ f  # on geom[1], world
            i, on = hit
            total[i] += f_W if g1 == on else -f_W
        out[k] = total
    return out
