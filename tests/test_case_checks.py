"""What a case declares is checked when it is made, before anything runs; a declared invariant is
computed, stored and judged like the built-in ones."""

import dataclasses
import functools
import json
import re

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.case import Case, CaseRecord, Invariant, Tolerance, case
from dalembert.harness.execute import Timing, execute
from dalembert.harness.matrix import spec
from dalembert.record import RunRecord
from dalembert.scene import Body, Joint, Scene, SceneError

TOL = Tolerance(1e-6, "a bound for the test")


def _scene():
    return Scene("s", [Body("b", 1.0, np.eye(3))], [Joint("free", "world", "b", [0, 0, 0, 1, 0, 0, 0], [0] * 6)],
                 gravity=(0.0, 0.0, 0.0))


def _case(**kw):
    args = dict(conserved=(), tolerances={"orientation": TOL})
    args.update(kw)
    return Case("mine", _scene(), 1.0, [0.0, 1.0], **args)


def _spin(tolerance=TOL, name="spin", scale=1.0):
    return Invariant(name, "angular velocity about body z", "rad/s", scale, tolerance,
                     lambda scene, traj: traj.bodies["b"].angular_velocity_body[:, 2])


def _problems(**kw):
    with pytest.raises(SceneError) as err:
        _case(**kw)
    assert str(err.value).startswith("case 'mine':")
    return err.value.problems


def test_unknown_conserved_name_suggests_the_right_one():
    (p,) = _problems(conserved=("enrgy",), tolerances={"energy": TOL})[:1]
    assert p.startswith("conserved[0]: unknown 'enrgy'") and "did you mean 'energy'" in p


def test_misspelled_tolerance_name_suggests_the_right_one():
    (p,) = _problems(tolerances={"orientaton": TOL})
    assert p.startswith("tolerances['orientaton']: unknown name") and "did you mean 'orientation'" in p


def test_tolerance_without_a_reason():
    (p,) = _problems(tolerances={"orientation": Tolerance(1e-6, "  ")})
    assert p.startswith("tolerances['orientation'].reason: empty")


def test_conserved_quantity_without_a_bound_and_a_bound_on_one_not_conserved():
    ps = _problems(conserved=("energy",), tolerances={"angular_momentum": TOL})
    assert any(p.startswith("tolerances['angular_momentum']: bounds 'angular_momentum'") for p in ps)
    assert any(p.startswith("conserved: 'energy' has no bound") for p in ps)


def test_declared_invariant_problems_name_the_field():
    ps = _problems(invariants=(_spin(name="energy"), _spin(name="rate_x", scale=0.0), "spin"))
    assert any(p.startswith("invariants[0] ('energy').name: 'energy' is a built-in name") for p in ps)
    assert any(p.startswith("invariants[1] ('rate_x').name: must be a lowercase identifier") for p in ps)
    assert any(p.startswith("invariants[1] ('rate_x').scale: must be a positive number") for p in ps)
    assert any(p.startswith("invariants[2]: expected an Invariant") for p in ps)
    (p,) = _problems(invariants=(_spin(), _spin()))
    assert "declared twice" in p


def test_factory_without_t_final_or_with_a_parameter_without_default_fails_at_registration():
    with pytest.raises(SceneError) as err:
        @case(tags=("test",))
        def no_horizon(mass=1.0):
            return _case()
    assert "case 'no_horizon'" in str(err.value) and "t_final: the factory has no t_final parameter" in str(err.value)
    with pytest.raises(SceneError, match="parameter 'mass': has no default"):
        @case(tags=("test",))
        def no_default(mass, t_final=1.0):
            return _case()


def test_declared_invariant_joins_the_tolerances_and_the_version():
    made = _case(invariants=(_spin(),))
    assert made.tolerances["spin"] is TOL
    assert made.version != _case(invariants=(_spin(scale=2.0),)).version
    assert _case().version == _case().version  # no invariants: the version payload is as before
    with pytest.raises(SceneError, match=r"tolerances\['spin'\]: also given by invariants"):
        _case(tolerances={"orientation": TOL, "spin": Tolerance(1.0, "another")}, invariants=(_spin(),))


def test_case_record_keeps_the_invariants_label_without_code():
    record = CaseRecord.from_case(make_case("heavy_top"), "closed form")
    back = CaseRecord.from_json(json.loads(json.dumps(record.to_json())))
    labels = {i.name: i for i in back.invariants}
    assert set(labels) == {"vertical_angular_momentum", "spin"}
    assert labels["spin"].unit == "rad/s" and labels["spin"].scale == pytest.approx(np.hypot(150.0, 4.61538))
    assert "pivot" in labels["vertical_angular_momentum"].description
    old = record.to_json()
    del old["invariants"]  # a store written before declared invariants
    assert CaseRecord.from_json(old).invariants == ()


def test_heavy_top_run_stores_and_judges_its_declared_invariants():
    made = make_case("heavy_top", t_final=0.05)
    run_spec = spec(made, "reference", Settings("rk4", dt=1e-3), {"t_final": 0.05})
    record, _ = execute(run_spec, Timing(min_repeats=1, min_total_s=0.0, max_repeats=1))
    assert record.ok, record.message
    assert {"energy", "vertical_angular_momentum", "spin"} <= set(record.drifts)
    assert record.drifts["spin"] < 1e-12  # C w3' = 0 for a symmetric top: rk4 keeps it to roundoff
    row = record.to_row()
    assert "drift_spin" in row and "drift_vertical_angular_momentum" in row
    assert RunRecord.from_row(row).drifts["spin"] == record.drifts["spin"]


def test_variants_and_hard_cases_stay_out_of_the_default_matrix():
    from dalembert.case import CASES, in_default_matrix, load_cases

    load_cases()
    default = {n for n, f in CASES.items() if in_default_matrix(f)}
    assert {"pendulum", "heavy_top", "chain"} <= default
    assert not {"pendulum_a01", "heavy_top_nutating", "chain_chaotic", "kovalevskaya_top"} & default


# Physically meaningless parameters (issue 42): each once ran to a stored "ok" (or to NaN and numpy
# warnings); every one is refused when the case is made, naming the case and the parameter.
MEANINGLESS = [
    ("chain", dict(length=0.0), "chain.length: must be positive (m), got 0.0"),
    ("pendulum", dict(radius=-0.01), "pendulum.radius: must be positive (m), got -0.01"),
    ("pivoted_rod", dict(length=1e-300), "pivoted_rod.length: 1e-300 (m) is below 1e-50"),
    ("free_top", dict(omega0=(1e200, 0.0, 0.0)), "free_top.omega0: (1e+200, 0.0, 0.0) (rad/s) is beyond 1e+50"),
    ("free_top", dict(omega0=(float("nan"), 0.0, 0.0)), "free_top.omega0: must be finite (rad/s)"),
    ("heavy_top", dict(inertia=(0.2, -0.4, 0.2)), "heavy_top.inertia: must be positive (kg m^2) in every component"),
    ("chain", dict(n=0), "chain.n: must be a whole number >= 1 (links), got 0"),
    ("n_four_bar", dict(n=2.5), "n_four_bar.n: must be a whole number >= 1"),
    ("pendulum", dict(gravity=float("inf")), "pendulum.gravity: must be finite (m/s^2)"),
    ("pendulum", dict(theta0="1"), "pendulum.theta0: must be a number (rad)"),
    ("pendulum", dict(t_final=-1.0), "pendulum.t_final: must be positive (s)"),
    ("particle_box", dict(spacing=(1.0, 2.0)), "particle_box.spacing: expected 3 numbers"),
]


@pytest.mark.parametrize("name,params,phrase", MEANINGLESS, ids=[f"{n}-{sorted(p)[0]}" for n, p, _ in MEANINGLESS])
def test_a_meaningless_parameter_is_refused_naming_it(name, params, phrase):
    from dalembert.case import load_cases

    factory = load_cases()[name]

    @functools.wraps(factory.func)  # (its signature: the parameters and their defaults)
    def never(**_):
        raise AssertionError("the factory ran")

    with pytest.raises(SceneError) as err:
        make_case(name, **params)
    assert str(err.value).startswith(f"case {name!r}:")
    (p,) = err.value.problems
    assert p.startswith(phrase) and " — " in p, p
    # refused before the factory runs: the same family with a factory that must not be called
    with pytest.raises(SceneError, match=re.escape(phrase)):
        dataclasses.replace(factory, func=never)(**params)


def test_every_registered_case_declares_its_lengths_masses_and_counts_positive():
    """The domains are declared, not guessed: a parameter named like a length, mass, radius or count
    in a registered case is declared positive (or a count), and its defaults lie in the domain."""
    from dalembert.case import CASES, load_cases

    load_cases()
    physical = {"length", "mass", "radius", "inertia", "spacing", "section", "moment", "com_distance", "com_offset",
                "sample_interval"}
    for name, factory in CASES.items():
        for key in set(factory.params) & physical:
            assert key in factory.positive, f"{name}.{key}: not declared positive"
        if "n" in factory.params:
            assert "n" in factory.counts, f"{name}.n: not declared a count"
        factory()  # the defaults lie in the domains (checked at registration too)


def test_a_domain_the_defaults_break_or_a_name_not_a_parameter_is_refused_at_registration():
    with pytest.raises(SceneError) as err:
        @case(tags=("test",), positive=("mass", "lenght"), counts=("n",))
        def bad_domain(mass=0.0, n=1.5, t_final=1.0):
            return _case()
    text = str(err.value)
    assert "positive: 'lenght' is not a parameter of it" in text
    with pytest.raises(SceneError) as err:
        @case(tags=("test",), positive=("mass",), counts=("n",))
        def bad_default(mass=0.0, n=1.5, t_final=1.0):
            return _case()
    ps = err.value.problems
    assert any(p.startswith("default: bad_default.mass: must be positive") for p in ps), ps
    assert any(p.startswith("default: bad_default.n: must be a whole number >= 1") for p in ps), ps


def test_a_factory_that_returns_no_case_or_one_named_otherwise_is_refused():
    from dalembert.case import CaseFactory

    def mine(t_final=1.0):
        return _case()

    def not_a_case(t_final=1.0):
        return {"name": "not_a_case"}

    made = CaseFactory("mine", mine, ("test",), {"t_final": "s"})()
    assert made.tags == ("test",) and made.params == {"t_final": 1.0} and made.units == {"t_final": "s"}
    with pytest.raises(SceneError, match="factory: returned dict, not a Case"):
        CaseFactory("not_a_case", not_a_case, (), {})()
    with pytest.raises(SceneError, match="name: the factory made a case named 'mine'"):
        CaseFactory("other", mine, (), {})()
