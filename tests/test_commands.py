"""Commands as modules, one API with the command line's flags, and inputs refused before anything
is written: empty values, refusals that used to leave a dead store, size guards, duplicates,
and a validation row that is the truth itself."""

import argparse
import inspect
import os
from types import SimpleNamespace

import pytest

from dalembert.harness import api
from dalembert.harness.cli import _parser, main
from dalembert.harness.commands import run as run_command
from dalembert.harness.selection import MAX_MODEL_PARTS, MAX_RUNS, select

# A run the tests can afford: one closed-form case, one step, a fraction of a second of motion.
SMALL = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
         "--param", "t_final=0.2", "--jobs", "1", "--quick"]


def _run_flags():
    sub = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction)).choices["run"]
    return [a for a in sub._actions if not isinstance(a, argparse._HelpAction)]


def _select(**flags):
    """``selection.select`` on the run flags ``flags`` (the rest at their defaults), on 1 core."""
    args = {a.dest: a.default for a in _run_flags()}
    args.update(flags)
    return select(SimpleNamespace(**args), 1)


# --- one API -------------------------------------------------------------------------------------

def test_every_run_flag_has_its_api_keyword():
    """A flag added to ``dalembert run`` only (no keyword in api.run, or in the command's run) fails here."""
    api_keywords = set(inspect.signature(api.run).parameters)
    command_keywords = set(inspect.signature(run_command.run).parameters)
    for action in _run_flags():
        keyword = run_command.KEYWORDS.get(action.dest, action.dest)
        assert keyword in api_keywords, f"{action.option_strings}: no api.run keyword {keyword!r}"
        assert keyword in command_keywords, f"{action.option_strings}: no commands.run.run keyword {keyword!r}"
    assert "debug" in api_keywords  # the global --debug, which run uses for Dask's log


def test_every_command_is_a_module_with_its_run():
    """cli.py only dispatches: each command's handler is the ``main`` of its own module, beside its ``run``."""
    import sys

    from dalembert.harness.cli import COMMANDS

    sub = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert set(COMMANDS) == set(sub.choices)
    for name, handler in COMMANDS.items():
        module = sys.modules[handler.__module__]
        assert module.__name__ == "dalembert.harness.commands." + name.replace("-", "_")
        assert handler is module.main and callable(module.run)


def test_a_command_runs_from_keywords(tmp_path, capsys):
    """truth's run from Python, refusing a parameter given twice as the command line does."""
    from dalembert.harness.commands import truth

    assert truth.run("particle_box", ["t_final=1"], csv=str(tmp_path / "box.csv")) == 0
    assert (tmp_path / "box.csv").read_text().startswith("t,body,")
    assert truth.run("particle_box", ["t_final=1", "t_final=2"], csv=str(tmp_path / "again.csv")) == 2
    assert "given twice" in capsys.readouterr().err and not (tmp_path / "again.csv").exists()


def test_the_api_refuses_an_unknown_parameter_as_the_cli_does(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="--param t_finl: no selected case has this parameter.*did you mean 't_final'"):
        api.run(cases=["free_top"], engines=["reference"], params={"t_finl": 1.0}, out=str(tmp_path / "x"))
    assert main(["run", "--case", "free_top", "--engine", "reference", "--param", "t_finl=1",
                 "--out", str(tmp_path / "x")]) == 2
    assert "did you mean 't_final'" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_api_values_are_typed_as_the_command_line_types_them():
    """A Python value goes through the command line's parser: a tuple is a vector, a list sweeps,
    an int where a float is expected is that float, a float where an int is expected is refused."""
    assert run_command._param_text("omega0", (0.0, 1.0, 1e-3)) == "omega0=0.0,1.0,0.001"
    assert run_command._param_text("spin", [5, 50.5]) == "spin=5,50.5"
    assert run_command._param_text("omega0", [(0, 1, 2), (0, 2, 2)]) == "omega0=0,1,2;0,2,2"
    chosen = _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                     param=run_command._texts("--param", {"t_final": 2, "omega0": [(0, 1, 2), (0, 2, 2)]},
                                              run_command._param_text))
    assert sorted(dict(s.params)["omega0"] for s in chosen.specs) == [(0.0, 1.0, 2.0), (0.0, 2.0, 2.0)]
    assert {dict(s.params)["t_final"] for s in chosen.specs} == {2.0}
    with pytest.raises(ValueError, match="--param n='2.5': expected int"):
        _select(case=["chain"], engine=["reference"], param=run_command._texts("--param", {"n": 2.5},
                                                                             run_command._param_text))


def test_the_api_runs_resumes_and_is_strict(tmp_path):
    """api.run with the command line's flags: quick, resume (nothing left to do), strict."""
    out = str(tmp_path / "top")
    runs = api.run(cases="free_top", engines=["reference"], integrators=["rk4"], dts=[1e-2],
                   params={"t_final": 0.2}, out=out, jobs=1, quick=True)
    assert list(runs["status"]) == ["ok"] and runs.attrs["store"] == out
    again = api.run(resume=out)
    assert again["key"].tolist() == runs["key"].tolist()
    with pytest.raises(ValueError, match="--resume .*--dt cannot change"):
        api.run(resume=out, dts=[1e-3])
    assert api.run(resume=out, strict=True)["status"].tolist() == ["ok"]


# --- empty values --------------------------------------------------------------------------------

@pytest.mark.parametrize("argv,flag", [
    (["run", "--resume", ""], "--resume"),
    (["run", "--scheduler", "", "--case", "free_top"], "--scheduler"),
    (["run", "--out", " "], "--out"),
    (["run", "--case", ""], "--case"),
    (["run", "--engine", "", "--case", "free_top"], "--engine"),
    (["validate", "--out", ""], "--out"),
    (["validate", "--case", ""], "--case"),
    (["truth", "free_top", "--csv", ""], "--csv"),
    (["report", ""], "RUN_DIR"),
    (["show-model", "free_top", "--engine", ""], "--engine"),
])
def test_an_empty_value_is_an_error_naming_its_flag(argv, flag, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert f"error: {flag}: empty" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # no default matrix started, no results/ made


@pytest.mark.parametrize("keyword,value,words", [
    ("resume", "", "--resume: empty"), ("scheduler", "", "--scheduler: empty"), ("out", "", "--out: empty"),
    ("search", "", "--search: empty"), ("engines", [], "--engine: an empty list"), ("dts", [], "--dt: no value"),
    ("tags", [""], "--tag: empty"),
])
def test_the_api_refuses_an_empty_value_too(keyword, value, words, tmp_path, monkeypatch):
    """An empty string or list is not "the default" in Python either (that is None)."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match=words):
        api.run(**{"cases": ["free_top"], keyword: value})
    assert not any(tmp_path.iterdir())


# --- refusals before the store -------------------------------------------------------------------

def test_a_case_that_cannot_be_computed_leaves_no_store(tmp_path, capfd, monkeypatch):
    """A truth that overflows (here the reference's truth made to, as an overflow in a case's closed form
    would) is refused with one message (numpy's warnings in it, not printed), nothing written, and the
    corrected command then uses the same directory; a parameter the case itself refuses (omega0 beyond its
    domain) leaves no store either."""
    import warnings

    import numpy as np

    import dalembert.reference as reference

    out = str(tmp_path / "top")
    assert main(["run", *SMALL, "--param", "omega0=1e200,0,0", "--out", out]) == 2
    err = capfd.readouterr().err
    assert "free_top.omega0" in err and not os.path.exists(out)
    real = reference.truth

    def overflowing(case):
        made = real(case)
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        made.bodies["top"].angular_velocity[-1, 0] = np.inf
        return made

    monkeypatch.setattr(reference, "truth", overflowing)
    assert main(["run", *SMALL, "--out", out]) == 2
    err = capfd.readouterr().err
    assert "case 'free_top' with" in err and "not finite" in err and "--param" in err
    assert "overflow encountered" in err and "RuntimeWarning" not in err and err.count("\n") == 1
    assert not os.path.exists(out)
    monkeypatch.setattr(reference, "truth", real)
    assert main(["run", *SMALL, "--out", out]) == 0


# --- size guards ---------------------------------------------------------------------------------

def test_a_huge_sweep_is_refused_before_its_values_are_made(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--param", "t_final=lin:1,2,100000000"]) == 2
    err = capsys.readouterr().err
    assert "100000000 values" in err and "--force" in err
    assert not any(tmp_path.iterdir())


def test_a_huge_model_is_refused_unless_forced(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--case", "chain", "--param", "n=1000000"]) == 2
    err = capsys.readouterr().err
    assert f"more than {MAX_MODEL_PARTS} parts" in err and "links" in err and "--force" in err
    assert not any(tmp_path.iterdir())
    forced = _select(case=["chain"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                     param=[f"n={MAX_MODEL_PARTS + 1}", "t_final=0.1"], force=True)
    assert {dict(s.params)["n"] for s in forced.specs} == {MAX_MODEL_PARTS + 1}


def test_a_matrix_of_too_many_runs_is_refused(monkeypatch):
    """The product of two sweeps, each within the limit, is more runs than MAX_RUNS."""
    side = int(MAX_RUNS ** 0.5) + 1
    with pytest.raises(ValueError, match=f"{side * side} case variants, more than {MAX_RUNS} runs"):
        _select(case=["free_top"], param=[f"t_final=lin:1,2,{side}", f"sample_interval=lin:0.01,0.02,{side}"])


# --- duplicates ----------------------------------------------------------------------------------

def test_a_repeated_name_counts_once_with_a_note():
    once = _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]])
    twice = _select(case=["free_top", "free_top"], engine=["reference", "reference"],
                    integrator=["rk4", "rk4"], dt=[[1e-2], [1e-2]])
    assert twice.specs == once.specs
    assert any(n.startswith("--case: free_top given more than once") for n in twice.notes)
    assert any(n.startswith("--engine: reference given more than once") for n in twice.notes)


def test_validate_counts_a_repeated_case_once():
    from dalembert.harness.validation import validation_specs

    notes = []
    assert validation_specs(["pivoted_rod", "pivoted_rod"], notes) == validation_specs(["pivoted_rod"])
    assert notes and "pivoted_rod given more than once" in notes[0]


@pytest.mark.parametrize("argv", [
    ["truth", "free_top", "--param", "t_final=1", "--param", "t_final=2", "--csv", "x.csv"],
    ["run", "--case", "free_top", "--param", "t_final=1", "--param", "t_final=2"],
    ["show-model", "pivoted_rod", "--engine", "mujoco", "--param", "length=1", "--param", "length=2"],
    ["show-model", "pivoted_rod", "--engine", "exudyn", "--option", "joints=redundant", "--option",
     "joints=minimal"],
])
def test_a_single_valued_thing_given_twice_is_refused_everywhere(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert "given twice" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_export_refuses_an_option_given_twice(tmp_path, capsys):
    out = str(tmp_path / "top")
    assert main(["run", *SMALL, "--out", out]) == 0
    capsys.readouterr()
    assert main(["export", out, "--option", "formulation=kane", "--option", "formulation=planar",
                 "--csv", str(tmp_path / "x.csv")]) == 2
    assert "--option formulation: given twice" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize("argv", [
    ["run", "--out", "a", "--out", "b"],
    ["run", "--jobs", "1", "--case", "free_top", "--jobs", "2"],
    ["validate", "--out", "a", "--out", "a"],
    ["export", "somewhere", "--case", "free_top", "--case", "pivoted_rod", "--csv", "x.csv"],
    ["compare", "a", "b", "--threshold", "3", "--threshold", "4"],
])
def test_a_single_valued_flag_given_twice_is_refused(argv, tmp_path, capsys, monkeypatch):
    """argparse would keep the last; which one was meant is a guess, so it is refused."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    assert "given twice" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


# --- validation: a truth with no independent check -----------------------------------------------

def test_the_truth_checked_against_itself_is_marked(tmp_path):
    """chain has no closed form: the run with the truth's own settings is marked as the truth
    itself (not "within tol yes"), the case says it has no independent check here; free_top's
    closed form is independent."""
    from dalembert.harness.validation import is_the_truth, to_markdown, write_csv

    out = str(tmp_path / "v")
    # (the planar formulation is chain's truth's; the free top, not planar, runs kane only: planar is refused)
    api.run(cases=["chain", "free_top"], engines=["reference"], integrators=["dop853"], rtols=[1e-12],
            options={"formulation": ["planar", "kane"]}, params={"t_final": 0.1}, out=out, jobs=1, quick=True)
    store = api.load(out)
    marked = {(r.case, r.settings.options["formulation"]): is_the_truth(r, store.case(r.case, r.case_version))
              for r in store.records()}
    assert marked == {("chain", "planar"): True, ("chain", "kane"): False, ("free_top", "kane"): False}
    md = to_markdown(store)
    chain, top = md.split("## chain")[1].split("## free_top")
    assert "— (the truth itself)" in chain and "no independent check" in chain
    assert "the truth itself" not in top and "closed form (independent" in top
    write_csv(store, tmp_path / "v.csv")
    text = (tmp_path / "v.csv").read_text()
    assert "is_the_truth" in text.splitlines()[0] and text.count("True") >= 1
