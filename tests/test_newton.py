"""Newton adapter (Newton 1.8 on Warp's CPU backend, float32): exact truths of its first-order solvers, what it
refuses, and the audit that Newton's defaults the scene does not ask for are off.

Warp compiles each of Newton's kernel modules on first launch and caches it on disk (``adapters.newton.engine``):
from a fresh clone the first model here costs tens of seconds of compilation on 2 cores, the others load their
kernels from that cache. Each test steps at most 1 s of model time.
"""

import numpy as np
import pytest
from installed import needs

# long: the first model compiles Newton's kernels (tens of seconds from a fresh clone)
pytestmark = [needs("newton", "warp", reason="Newton is not installed: pip install dalembert[newton]"), pytest.mark.long]

from dalembert import Settings, make_case, spatial  # noqa: E402
from dalembert.adapters import get_adapter  # noqa: E402

ADAPTER = get_adapter("newton")
EPS32 = float(np.finfo(np.float32).eps)  # 1.19e-7: Newton computes in float32
# A first-order method's global error halves with the step: log2 of the ratio of the errors at dt and dt/2 is 1
# up to the next term of the error's expansion; measured 1.00 (Featherstone, pendulum, 1 s at 1e-3 and 5e-4). A
# second-order error (a scheme of higher order than declared) gives 2, a float32-dominated one ~0.
ORDER_SLACK = 0.25
# Free fall under constant gravity: semi-implicit Euler's exact position after n steps is
# g dt^2 n (n + 1) / 2 = g (t^2 + t dt) / 2, the velocity g t; in float32 each of n steps rounds a sum of size
# |x| (|v|) once, at worst all one sign: n EPS32 |x|. Measured 3e-6 m on 500 steps (-1.2274 m), against
# a method error g t dt / 2 = 2.4e-3 m that the test also resolves.
def fall_tol(n, size):
    return n * EPS32 * size


# Steel's angular damping scales the angular velocity by (1 - d dt) every step, so a torque-free body's kinetic
# energy by (1 - d dt)^(2n); besides it the energy moves by the method's own drift, measured 1.5e-4 of it on the
# free top over 1 s at dt 1e-3 (and NaN-free). 1e-3 bounds that drift with room, far below the 63 % the damping
# takes at d = 0.5 /s.
STEEL_ENERGY_REL_TOL = 1e-3


def _run(case, family, dt, times, **options):
    settings = Settings(family, dt=dt, options={k: str(v) for k, v in options.items()})
    p = ADAPTER.prepare(case.scene, np.asarray(times, dtype=float), settings)
    out = ADAPTER.run(p)
    return p, out


@pytest.fixture(scope="module")
def pendulum():
    return make_case("pendulum")


@pytest.fixture(scope="module")
def top():
    return make_case("free_top")


class TestTruths:
    def test_pendulum_featherstone_first_order(self, pendulum):
        """The pendulum's angle against its closed form (elliptic functions) at dt and dt/2: a first-order error."""
        times = np.linspace(0.0, 1.0, 11)
        exact = pendulum.exact(times).joints["rod"].q[:, 0]
        errs = []
        for dt in (1e-3, 5e-4):
            _, out = _run(pendulum, "featherstone", dt, times)
            errs.append(np.abs(out.trajectory.joints["rod"].q[:, 0] - exact).max())
        assert abs(np.log2(errs[0] / errs[1]) - 1.0) < ORDER_SLACK, errs

    def test_free_fall_is_semi_implicit_eulers(self):
        """The particle box's COM falls as semi-implicit Euler's closed form, not as the exact parabola."""
        case = make_case("particle_box")
        n, dt = 500, 1e-3
        t = n * dt
        p, out = _run(case, "featherstone", dt, [0.0, t])
        body = case.scene.bodies[0].name
        g = np.asarray(case.scene.gravity)
        x = out.trajectory.bodies[body].position[-1]
        v = out.trajectory.bodies[body].velocity[-1]
        euler = 0.5 * g * (t * t + t * dt)
        assert np.abs(x - euler).max() < fall_tol(n, np.abs(euler).max()), (x, euler)
        assert np.abs(v - g * t).max() < fall_tol(n, np.abs(g * t).max()), v
        # the closed form resolves the method: the exact parabola is g t dt / 2 = 2.4 mm away, 33 bounds
        assert np.abs(x - 0.5 * g * t * t).max() > 10 * fall_tol(n, np.abs(euler).max())

    def test_free_top_first_order(self, top):
        """The torque-free top's attitude against its closed form (Jacobi elliptic functions) at dt and dt/2.
        (Not Steel's: its error grows as the step shrinks, 3.7e-4 rad at 1e-3 s, 8.8e-4 at 5e-4, measured.)"""
        family = "featherstone"
        times = np.linspace(0.0, 1.0, 11)
        exact = top.exact(times).bodies["top"].quaternion
        errs = []
        for dt in (1e-3, 5e-4):
            _, out = _run(top, family, dt, times)
            errs.append(spatial.rotation_angle(out.trajectory.bodies["top"].quaternion, exact).max())
        assert abs(np.log2(errs[0] / errs[1]) - 1.0) < ORDER_SLACK, errs

    def test_steel_angular_damping_reaches_the_engine(self, top):
        """Steel's angular damping (0.05 /s by default in Newton) is 0 here; given, it takes (1 - d dt)^(2n) of the
        kinetic energy."""
        times, dt, d = np.array([0.0, 1.0]), 1e-3, 0.5
        inertia = top.scene.bodies[0].inertia_matrix

        def energy(out):
            tr = out.trajectory.bodies["top"]
            R = spatial.quat_to_matrix(spatial.quat_normalize(tr.quaternion))
            w_B = np.einsum("nji,nj->ni", R, tr.angular_velocity)
            return 0.5 * np.einsum("ni,ij,nj->n", w_B, inertia, w_B)

        p, out = _run(top, "steel", dt, times)
        e = energy(out)
        assert abs(e[-1] / e[0] - 1.0) < STEEL_ENERGY_REL_TOL, e
        assert ADAPTER.audit(p, out)["solver_settings"]["angular_damping"] == 0.0
        p, out = _run(top, "steel", dt, times, angular_damping=d)
        e = energy(out)
        assert abs(e[-1] / e[0] / (1.0 - d * dt) ** (2 * 1000) - 1.0) < STEEL_ENERGY_REL_TOL, e
        assert ADAPTER.audit(p, out)["solver_settings"]["angular_damping"] == d


class TestRun:
    def test_audit_reads_back_what_newton_ran(self, pendulum):
        p, out = _run(pendulum, "xpbd", 1e-3, np.asarray(pendulum.times)[:3])
        audit = ADAPTER.audit(p, out)
        assert audit["device"] == "cpu" and audit["number_type"] == "float32"
        assert audit["gravity_float32"][2] == float(np.float32(-9.81)) != -9.81  # stored in float32
        assert audit["gravity"] == (0.0, 0.0, -9.81)  # that float32's shortest decimal
        assert audit["integrator"] == "Newton SolverXPBD"
        assert audit["solver_settings"] == {"angular_damping": 0.0, "iterations": 2, "joint_linear_relaxation": 0.7,
                                            "joint_angular_relaxation": 0.4, "joint_linear_compliance": 0.0,
                                            "joint_angular_compliance": 0.0}
        assert audit["joint_armature_max"] == audit["joint_passive_damping_max"] == audit["joint_limit_ke_max"] == 0
        assert out.n_steps == int(p.steps.sum()) == 20

    def test_featherstone_damping_off_unless_asked(self, pendulum):
        p, out = _run(pendulum, "featherstone", 1e-3, np.asarray(pendulum.times)[:2])
        assert ADAPTER.audit(p, out)["solver_settings"]["angular_damping"] == 0.0
        assert p.solver.angular_damping == 0.0  # Newton's default is 0.05

    def test_defaults_engine_keeps_newtons_damping(self, top):
        """``defaults=engine`` builds with Newton's own angular damping (0.05 /s in Featherstone), read back."""
        p, out = _run(top, "featherstone", 1e-3, [0.0, 0.01], defaults="engine")
        assert p.solver.angular_damping == 0.05
        assert ADAPTER.audit(p, out)["solver_settings"]["angular_damping"] == 0.05
        assert "defaults=engine" in ADAPTER.describe(top.scene, p.settings)

    def test_repeatable(self, pendulum):
        times = np.asarray(pendulum.times)[:6]
        p, out = _run(pendulum, "steel", 1e-3, times)
        again = ADAPTER.run(p).trajectory.bodies["rod"].quaternion
        assert np.array_equal(out.trajectory.bodies["rod"].quaternion, again)

    def test_non_finite_state_ends_the_run(self, pendulum):
        """Newton's semi-implicit solver at its default joint stiffness (1e4) blows up on the pendulum (the rod's
        5e-5 kg m^2 about its own axis against the penalty spring at dt 1e-3): NaN from there on, no exception."""
        p, out = _run(pendulum, "semi_implicit", 1e-3, np.asarray(pendulum.times)[:101])
        q = out.trajectory.bodies["rod"].position
        assert "non-finite state" in out.info["message"] and np.isnan(q[-1]).all() and np.isfinite(q[0]).all()
        assert out.n_steps < int(p.steps.sum())


class TestRefusals:
    def test_loops_springs_contact(self):
        for name, words in (("four_bar", "closed kinematic loops"), ("bouncing_ball", "contact"),
                            ("flyball_governor", "spring-dampers")):
            reason = ADAPTER.unsupported(make_case(name).scene, Settings("featherstone", dt=1e-3))
            assert reason and words in reason, (name, reason)

    def test_bad_option_named_before_anything_runs(self, pendulum):
        with pytest.raises(ValueError, match="options.iterations"):
            ADAPTER.check(pendulum.scene, pendulum.times, Settings("xpbd", dt=1e-3, options={"iterations": "0"}))
        with pytest.raises(ValueError, match="options.joint_attach_ke: only semi_implicit"):
            ADAPTER.check(pendulum.scene, pendulum.times,
                          Settings("featherstone", dt=1e-3, options={"joint_attach_ke": "1e5"}))


def test_check_engine_featherstone():
    from dalembert.testing import check_engine

    check_engine("newton", integrators=["featherstone"])
