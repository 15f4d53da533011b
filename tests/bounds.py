"""Bounds shared by the engine tests (test_mujoco, test_pinocchio, test_exudyn) and test_roundoff.

Upper bounds on a fourth-order fixed-step method (RK4, Exudyn's rk44) at dt = 1e-3 against the
closed forms of the canonical cases. The rod's angle and the box's fall are quadratic in t, which
any Runge-Kutta method of order >= 2 integrates exactly: what remains is roundoff, at most about
one rounding per step all of one sign, N eps |x| (2000 steps on 12 rad: 5e-12 rad; 20000 steps
on a 1960 m fall: 4e-9 m). The top's attitude carries the method's truncation, C dt^4 t: each
engine's order test asserts the fourth order, and 4.9e-9 rad at dt = 1e-2 over 2 s makes it
5e-12 rad at 1e-3 over 20 s. Measured (rod angle, rod reaction, top, box COM, box attitude):
MuJoCo 4.0.0 8.5e-14 rad, 8.7e-14 N, 5.3e-12 rad, 1.1e-10 m, 4.7e-14 rad; Pinocchio 4.1.0
1.0e-13 rad, 1.1e-13 N, 5.3e-12 rad, 6.5e-10 m, 2.3e-13 rad; Exudyn 1.13.6 2.9e-13 rad,
3.5e-13 N, 9.0e-12 rad, 1.9e-9 m, 2.6e-12 rad.
"""

ROD_ANGLE_TOL = 1e-10  # rad: 20x the worst-case roundoff of 2000 steps
ROD_REACTION_TOL = 1e-9  # N: m a - F from the same exact motion; roundoff on reactions of up to 72 N
TOP_ORIENTATION_TOL = 1e-8  # rad: 2000x the truncation (the order tests pin the method)
BOX_COM_TOL = 1e-8  # m: 2.5x the worst-case roundoff of the fall
BOX_ORIENTATION_TOL = 1e-8  # rad: as TOP_ORIENTATION_TOL, on a slower spin (~1.4 rad/s)
# Against the reference (Kane, DOP853 at 1e-12): RK4 at dt = 1e-3 over 1 s on the test scenes has
# truncation error ~1e-11; frames mixed up would give O(1).
CROSS_CHECK_TOL = 1e-8
# Observed order, log2 of the error ratio between dt and dt/2: the error is the max over time of
# C(t) dt^p plus a next term O(dt) relative (measured 4.000 for RK4 on the top from 1e-2 to 5e-3,
# 2.000 for Pinocchio's rk4-naive).
ORDER_SLACK = 0.3
