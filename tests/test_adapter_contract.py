"""One contract over every registered engine (engine x feature): option declarations and refusals, ``describe``,
the typed prepared model. The physics each engine gets right or wrong is in its own ``test_<engine>*.py``; the run
contract over every case (sampling, repeatability, the audit's gravity) is ``test_run_matrix``'s
``check_adapter``."""

import dataclasses
import re

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import Adapter, Option, Prepared, get_adapter
from engine_runs import real_engines

# Every registered engine but the suite's own test adapters (registered by whichever test module was collected first)
ENGINES = real_engines()
# A jointed tree with a load that every engine runs with its defaults (MJX too: a hinge, an actuator), on a short
# horizon: these tests build models, they do not judge motion.
CASE = "pivoted_rod"
T_FINAL = 0.1  # s: 10 samples


def _installed(engine):
    adapter = get_adapter(engine)
    try:
        adapter.version()
    except ImportError as e:
        pytest.skip(f"{engine} is not installed: {e}")
    return adapter


def _settings(adapter, options=None, integrator=None):
    """Settings for ``integrator`` (default: the engine's first), the case's sample interval as dt or the
    contract's tolerance."""
    name = integrator or next(iter(adapter.integrators))
    if adapter.integrators[name].fixed_step:
        return Settings(name, dt=1e-2, options=options or {})
    return Settings(name, rtol=1e-6, atol=1e-6, options=options or {})


def _options():
    """(engine, option name) for every option an engine declares."""
    return [(e, o) for e in ENGINES for o in get_adapter(e).options]


@pytest.mark.parametrize("engine", ENGINES)
def test_every_option_an_integrator_takes_is_declared_once(engine):
    """Each option name in an ``IntegratorSpec`` has its ``Option`` (values, default), and each declared option
    is taken by some integrator; a default is one of the choices, and ``only`` names the engine's integrators."""
    adapter = get_adapter(engine)
    named = {o for spec in adapter.integrators.values() for o in spec.options}
    assert named == set(adapter.options), (named, set(adapter.options))
    for name, option in adapter.options.items():
        assert isinstance(option, Option) and option.description, name
        if option.choices and option.default is not None:
            assert option.default in option.choices, name
        assert set(option.only) <= set(adapter.integrators), name


@pytest.mark.parametrize("engine,option", _options())
def test_a_bad_option_value_is_refused_before_anything_runs(engine, option):
    """A value an option does not take raises ValueError from ``check`` naming ``options.<name>`` and what it
    takes; every declared value passes the option check."""
    adapter = get_adapter(engine)
    declared = adapter.options[option]
    case = make_case(CASE, t_final=T_FINAL)
    integrator = declared.only[0] if declared.only else next(i for i, s in adapter.integrators.items()
                                                            if option in s.options)
    bad = "bogus" if declared.choices else "-inf"
    with pytest.raises(ValueError, match=f"options.{option}: .*{re.escape(declared.allowed())}"):
        adapter.check(case.scene, case.times, _settings(adapter, {option: bad}, integrator))
    for good in declared.choices or [v for v in (declared.minimum, declared.maximum, declared.default)
                                     if v is not None]:
        assert declared.problem(option, good, integrator) is None, good


@pytest.mark.parametrize("engine", ENGINES)
def test_an_option_no_integrator_of_the_engine_takes_is_refused(engine):
    """An option the engine does not declare for the integrator (MuJoCo's ``loads`` given to MJX, a misspelling)
    raises ValueError naming it and what the integrator takes."""
    adapter = get_adapter(engine)
    case = make_case(CASE, t_final=T_FINAL)
    taken = ["loads"] if engine == "mjx" else []  # MuJoCo's option, which MJX does not take
    for name in taken + ["nonsense"]:
        with pytest.raises(ValueError, match=rf"options: \['{name}'\] unknown to {engine} "):
            adapter.check(case.scene, case.times, _settings(adapter, {name: "x"}))


@pytest.mark.parametrize("engine,option", [(e, o) for e, o in _options() if get_adapter(e).options[o].only])
def test_an_option_only_some_integrators_take_is_refused_for_the_others(engine, option):
    adapter = get_adapter(engine)
    declared = adapter.options[option]
    other = next(i for i, s in adapter.integrators.items() if option in s.options and i not in declared.only)
    case = make_case(CASE, t_final=T_FINAL)
    good = declared.choices[0] if declared.choices else declared.default or declared.maximum
    with pytest.raises(ValueError, match=f"options.{option}: only {declared.only[0]}"):
        adapter.check(case.scene, case.times, _settings(adapter, {option: good}, other))


def test_a_number_option_is_checked_against_its_bounds():
    option = Option(minimum=0.0, maximum=1.0, description="a fraction")
    assert option.problem("f", "0.5", "any") is None  # (the command line gives strings)
    assert "out of range" in option.problem("f", 2, "any")
    assert "expected a number" in option.problem("f", "half", "any")
    assert "out of range" in option.problem("f", float("nan"), "any")
    positive = Option(exclusive_minimum=0.0, description="a tolerance")
    assert "a number > 0" in positive.problem("tol", 0.0, "any")
    assert positive.problem("tol", 1e-300, "any") is None


def test_the_reference_declares_every_formulation_of_the_solver():
    from dalembert.reference.solver import FORMULATIONS

    assert get_adapter("reference").options["formulation"].choices == tuple(FORMULATIONS)


# Scenes on which the engines' options change the model they build: a free body (Exudyn's ``node``), a jointed
# tree with a load (``joints``, ``loads``), a weld (``welds``)
OPTION_CASES = ("free_top", CASE, "particle_box_welded")


@pytest.mark.parametrize("engine", [e for e in ENGINES
                                    if any(o.default is not None for o in get_adapter(e).options.values())])
def test_a_run_without_an_option_builds_what_its_declared_default_builds(engine):
    """Leaving an option out refuses and builds (``unsupported``, ``describe``) as giving its declared
    ``Option.default`` does: what builds the model reads the declaration, not a default of its own. Not vacuous:
    some other declared value builds another model."""
    adapter = _installed(engine)
    other_models = []
    for name in OPTION_CASES:
        scene = make_case(name, t_final=T_FINAL).scene
        for key, option in adapter.options.items():
            if option.default is None:  # the engine's own or the scene's choice: nothing declared to compare
                continue
            integrator = option.only[0] if option.only else next(i for i, s in adapter.integrators.items()
                                                                if key in s.options)
            left_out, given = _settings(adapter, integrator=integrator), _settings(adapter, {key: option.default},
                                                                                   integrator)
            refusal = adapter.unsupported(scene, left_out)
            assert refusal == adapter.unsupported(scene, given), (name, key)
            if refusal is not None:
                continue
            model = adapter.describe(scene, left_out)
            assert model == adapter.describe(scene, given), (name, key)
            for value in option.choices:
                other = _settings(adapter, {key: value}, integrator)
                if value != option.default and adapter.unsupported(scene, other) is None \
                        and adapter.describe(scene, other) != model:
                    other_models.append((name, key, value))
    assert other_models, f"no declared value of {engine}'s options changes the model on {OPTION_CASES}"


@pytest.mark.parametrize("engine", ENGINES)
def test_describe_gives_the_model_as_text(engine):
    adapter = _installed(engine)
    case = make_case(CASE, t_final=T_FINAL)
    text = adapter.describe(case.scene, _settings(adapter))
    assert isinstance(text, str) and text.strip()


def test_describe_defaults_to_no_model_text():
    assert Adapter().describe(make_case(CASE).scene, Settings("rk4", dt=1e-2)) == ""


@pytest.mark.parametrize("engine", ENGINES)
def test_prepare_returns_a_frozen_documented_prepared_model(engine):
    """``prepare`` returns the engine's ``Prepared`` subclass: frozen, each of its fields documented in its
    docstring, and read as attributes only (not by name: ``prepared["times"]`` is a TypeError)."""
    adapter = _installed(engine)
    case = make_case(CASE, t_final=T_FINAL)
    settings = _settings(adapter)
    adapter.check(case.scene, case.times, settings)
    prepared = adapter.prepare(case.scene, case.times, settings)
    cls = type(prepared)
    assert isinstance(prepared, Prepared) and cls is not Prepared, cls
    assert np.array_equal(prepared.times, case.times) and prepared.scene is case.scene
    own = [f.name for f in dataclasses.fields(cls) if f.name not in {g.name for g in dataclasses.fields(Prepared)}]
    assert own, cls
    docs = "".join(c.__doc__ for c in cls.__mro__ if issubclass(c, Prepared) and c is not Prepared)
    for name in own:  # numpydoc: "name : type — ..." (or "a, b : ..."), in the class's or a base's docstring
        assert f"{name} :" in docs or f"{name}, " in docs, f"{cls.__name__}.{name} is not documented"
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(prepared, own[0], None)
    with pytest.raises(TypeError, match="not subscriptable"):
        prepared["times"]


def _engine_integrators():
    """(engine, integrator): every integrator of each engine, but one of an engine that JIT-compiles each
    (MJX: ~5-15 s a compilation on 2 cores; its rollout is one program whatever the integrator)."""
    out = []
    for e in ENGINES:
        integrators = list(get_adapter(e).integrators)
        out += [(e, i) for i in (integrators[:1] if e == "mjx" else integrators)]
    return out


@pytest.mark.parametrize("engine,integrator", _engine_integrators())
def test_a_run_writes_no_files_and_prints_nothing(engine, integrator, tmp_path, monkeypatch, capfd):
    """Contract point 9, at the level of file descriptors (an engine's C++ prints too): build, run, read back and
    audit in an empty working directory."""
    adapter = _installed(engine)
    monkeypatch.chdir(tmp_path)
    case = make_case(CASE, t_final=T_FINAL)
    settings = _settings(adapter, integrator=integrator)
    adapter.check(case.scene, case.times, settings)
    if adapter.unsupported(case.scene, settings):
        pytest.skip(adapter.unsupported(case.scene, settings))
    prepared = adapter.prepare(case.scene, case.times, settings)
    outcome = adapter.run(prepared)
    assert outcome.trajectory.is_finite()
    adapter.audit(prepared, outcome)
    assert list(tmp_path.iterdir()) == []
    assert capfd.readouterr() == ("", "")
