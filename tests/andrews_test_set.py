"""Andrews' squeezing mechanism in the Test Set's own equations: a second formulation, sharing nothing
with the reference solver but the parameters.

The equations are those of ``andfunc`` in ``pkg/deTestSet/src/Ex_andrews.f`` (repository
``rforge/bvpsolve``, "derived from the Test Set for IVP solvers", andrews.F rev. 1.2): the seven angles
``q = (beta, Theta, gamma, Phi, delta, Omega, epsilon)``, their mass matrix ``M(q)`` (7, 7), forces
``f(q, q')`` (7,) (motor, spring, velocity terms) and six constraints ``g(q) = 0`` with Jacobian
``G = dg/dq`` (6, 7), as the index-3 DAE ``M q'' = f - G^T lambda``, ``g(q) = 0``. Here in index 1: the
second derivative of the constraints, ``G q'' + gamma(q, q') = 0``, where ``gamma`` is ``g``'s second
derivative along ``q'`` (every term of ``g`` is ``a cos(phi)`` or ``a sin(phi)`` of one angle or a sum
of two, so its contribution is minus itself times that angle's rate squared, written out below), and

    [M  G^T] [q''   ]   [ f     ]
    [G  0  ] [lambda] = [-gamma ]

solved by ``numpy.linalg.solve`` at every evaluation; integrated by scipy's DOP853 without
projection (over the 30 ms the drift stays at the integration error).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["constraints", "accelerations", "integrate"]


def constraints(q, p):
    """``g(q)`` (6,), m: point E through bodies 1-2 minus E through body 3 (rows 1-2), through bodies
    5-4 (rows 3-4) and through bodies 7-6 (rows 5-6), x then y."""
    be, th, ga, ph, de, om, ep = q
    e12x = p["rr"] * np.cos(be) - p["d"] * np.cos(be + th)
    e12y = p["rr"] * np.sin(be) - p["d"] * np.sin(be + th)
    return np.array([e12x - p["ss"] * np.sin(ga) - p["xb"],
                     e12y + p["ss"] * np.cos(ga) - p["yb"],
                     e12x - p["e"] * np.sin(ph + de) - p["zt"] * np.cos(de) - p["xa"],
                     e12y + p["e"] * np.cos(ph + de) - p["zt"] * np.sin(de) - p["ya"],
                     e12x - p["zf"] * np.cos(om + ep) - p["u"] * np.sin(ep) - p["xa"],
                     e12y - p["zf"] * np.sin(om + ep) + p["u"] * np.cos(ep) - p["ya"]])


def accelerations(q, qd, p):
    """``q''`` (7,) (rad/s^2) and ``lambda`` (6,) (N) at angles ``q`` and rates ``qd`` (7,)."""
    rr, d, da, e, ea, ss, sa, sb, sc, sd = (p[k] for k in ("rr", "d", "da", "e", "ea", "ss", "sa", "sb", "sc", "sd"))
    ra, ta, tb, u, ua, ub, zf, zt, fa = (p[k] for k in ("ra", "ta", "tb", "u", "ua", "ub", "zf", "zt", "fa"))
    m1, m2, m3, m4, m5, m6, m7 = (p[f"m{k}"] for k in range(1, 8))
    i1, i2, i3, i4, i5, i6, i7 = (p[f"i{k}"] for k in range(1, 8))
    be, th, ga, ph, de, om, ep = q
    bep, thp, gap, php, dep, omp, epp = qd
    sibe, sith, siga, siph, side, siom, siep = np.sin(q)
    cobe, coth, coga, coph, code, coom, coep = np.cos(q)
    sibeth, cobeth = np.sin(be + th), np.cos(be + th)
    siphde, cophde = np.sin(ph + de), np.cos(ph + de)
    siomep, coomep = np.sin(om + ep), np.cos(om + ep)

    M = np.zeros((7, 7))
    M[0, 0] = m1 * ra**2 + m2 * (rr**2 - 2 * da * rr * coth + da**2) + i1 + i2
    M[1, 0] = M[0, 1] = m2 * (da**2 - da * rr * coth) + i2
    M[1, 1] = m2 * da**2 + i2
    M[2, 2] = m3 * (sa**2 + sb**2) + i3
    M[3, 3] = m4 * (e - ea) ** 2 + i4
    M[4, 3] = M[3, 4] = m4 * ((e - ea) ** 2 + zt * (e - ea) * siph) + i4
    M[4, 4] = m4 * (zt**2 + 2 * zt * (e - ea) * siph + (e - ea) ** 2) + m5 * (ta**2 + tb**2) + i4 + i5
    M[5, 5] = m6 * (zf - fa) ** 2 + i6
    M[6, 5] = M[5, 6] = m6 * ((zf - fa) ** 2 - u * (zf - fa) * siom) + i6
    M[6, 6] = m6 * ((zf - fa) ** 2 - 2 * u * (zf - fa) * siom + u**2) + m7 * (ua**2 + ub**2) + i6 + i7

    xd, yd = sd * coga + sc * siga + p["xb"], sd * siga - sc * coga + p["yb"]  # D, the spring's end on body 3
    length = np.hypot(xd - p["xc"], yd - p["yc"])
    force = -p["c0"] * (length - p["l0"]) / length
    fx, fy = force * (xd - p["xc"]), force * (yd - p["yc"])
    f = np.array([p["mom"] - m2 * da * rr * thp * (thp + 2 * bep) * sith,
                  m2 * da * rr * bep**2 * sith,
                  fx * (sc * coga - sd * siga) + fy * (sd * coga + sc * siga),
                  m4 * zt * (e - ea) * dep**2 * coph,
                  -m4 * zt * (e - ea) * php * (php + 2 * dep) * coph,
                  -m6 * u * (zf - fa) * epp**2 * coom,
                  m6 * u * (zf - fa) * omp * (omp + 2 * epp) * coom])

    G = np.zeros((6, 7))
    G[0::2, 0] = -rr * sibe + d * sibeth  # (rows 1, 3, 5: x of E through bodies 1-2)
    G[0::2, 1] = d * sibeth
    G[1::2, 0] = rr * cobe - d * cobeth
    G[1::2, 1] = -d * cobeth
    G[0, 2], G[1, 2] = -ss * coga, -ss * siga
    G[2, 3], G[2, 4] = -e * cophde, -e * cophde + zt * side
    G[3, 3], G[3, 4] = -e * siphde, -e * siphde - zt * code
    G[4, 5], G[4, 6] = zf * siomep, zf * siomep - u * coep
    G[5, 5], G[5, 6] = -zf * coomep, -zf * coomep - u * siep

    w_b, w_bt, w_g = bep**2, (bep + thp) ** 2, gap**2
    w_pd, w_d, w_oe, w_e = (php + dep) ** 2, dep**2, (omp + epp) ** 2, epp**2
    gx12 = -rr * cobe * w_b + d * cobeth * w_bt  # x of E through bodies 1-2, second derivative
    gy12 = -rr * sibe * w_b + d * sibeth * w_bt
    gamma = np.array([gx12 + ss * siga * w_g, gy12 - ss * coga * w_g,
                      gx12 + e * siphde * w_pd + zt * code * w_d, gy12 - e * cophde * w_pd + zt * side * w_d,
                      gx12 + zf * coomep * w_oe + u * siep * w_e, gy12 + zf * siomep * w_oe - u * coep * w_e])

    K = np.zeros((13, 13))
    K[:7, :7], K[:7, 7:], K[7:, :7] = M, G.T, G
    x = np.linalg.solve(K, np.concatenate([f, -gamma]))
    return x[:7], x[7:]


def integrate(q0, times, p, tol):
    """The angles (n, 7) and rates (n, 7) at ``times`` (s) from rest at ``q0`` (7,), by scipy's DOP853 at
    ``rtol = atol = tol`` (dense output)."""
    def rhs(t, y):
        return np.concatenate([y[7:], accelerations(y[:7], y[7:], p)[0]])

    sol = solve_ivp(rhs, (times[0], times[-1]), np.concatenate([q0, np.zeros(7)]), method="DOP853", rtol=tol,
                    atol=tol, t_eval=times)
    assert sol.success, sol.message
    return sol.y[:7].T, sol.y[7:].T
