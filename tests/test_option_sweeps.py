"""An engine option swept as a case parameter is: ``--option KEY=V1,V2`` / ``log:a,b,n`` / ``lin:a,b,n`` (the
parser of ``--param``'s sweeps), each value its own run, checked against the option's declaration and counted by
the size guard before anything is written; ``api.run(options=...)`` takes a list the same way."""

import numpy as np
import pytest

from dalembert.harness import selection
from dalembert.harness.cli import main
from dalembert.harness.commands import run as run_command
from test_commands import _select

# MuJoCo's contact case and its numeric option (adapters/mujoco/contact.py CONTACT_OPTIONS).
MUJOCO = dict(case=["block_on_incline"], engine=["mujoco"], integrator=["implicitfast"])


def _timeconsts(chosen):
    return [dict(s.settings.options)["contact_timeconst"] for s in chosen.specs]


def test_a_log_grid_of_an_option_is_a_run_per_value_and_step():
    pytest.importorskip("mujoco")
    chosen = _select(**MUJOCO, dt=[[1e-3, 1e-2]], option=["contact_timeconst=log:0.002,0.05,5"])
    grid = np.geomspace(0.002, 0.05, 5)
    assert len(chosen.specs) == 10 and len(set(chosen.specs)) == 10
    assert sorted({float(v) for v in _timeconsts(chosen)}) == pytest.approx(grid, rel=0, abs=0)
    assert sorted((s.settings.dt, dict(s.settings.options)["contact_timeconst"]) for s in chosen.specs) == sorted(
        (dt, repr(float(v))) for dt in (1e-3, 1e-2) for v in grid)


def test_an_option_given_once_keeps_its_text_and_a_list_sweeps_it():
    """One value is the text it always was (the run's key unchanged); a comma list is a run per value."""
    once = _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                   option=["formulation=kane"])
    assert [dict(s.settings.options) for s in once.specs] == [{"formulation": "kane"}]
    two = _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                  option=["formulation=kane,newton-euler"])  # (planar would be refused: a top is not planar)
    assert [dict(s.settings.options)["formulation"] for s in two.specs] == ["kane", "newton-euler"]
    assert once.specs[0] == two.specs[0]


def test_the_api_sweeps_an_option_from_a_list_as_the_command_line_does():
    pytest.importorskip("mujoco")
    texts = run_command._texts("--option", {"contact_timeconst": [0.01, 0.02]}, run_command._option_text)
    assert texts == ["contact_timeconst=0.01,0.02"]
    assert run_command._option_text("impratio", 2.0) == "impratio=2.0"  # a single value: its str, as before
    api = _select(**MUJOCO, dt=[[1e-3]], option=texts)
    cli = _select(**MUJOCO, dt=[[1e-3]], option=["contact_timeconst=0.01,0.02"])
    assert api.specs == cli.specs and _timeconsts(api) == ["0.01", "0.02"]


def test_a_swept_value_out_of_its_declared_range_is_refused_before_the_store(tmp_path, capsys):
    pytest.importorskip("mujoco")
    out = tmp_path / "x"
    assert main(["run", "--case", "block_on_incline", "--engine", "mujoco", "--integrator", "implicitfast",
                 "--dt", "1e-3", "--option", "contact_timeconst=0.01,-0.02", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--option contact_timeconst=-0.02: -0.02 is out of range — give a number > 0" in err
    assert not out.exists()


def test_a_grid_of_an_option_that_takes_names_is_refused():
    with pytest.raises(ValueError, match="--option formulation=lin:0,1,3: a lin: grid sweeps a real number; "
                                         "'formulation' is one of"):
        _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                option=["formulation=lin:0,1,3"])
    with pytest.raises(ValueError, match="--option formulation=kane,: an empty value"):
        _select(case=["free_top"], engine=["reference"], integrator=["rk4"], dt=[[1e-2]],
                option=["formulation=kane,"])
    pytest.importorskip("mujoco")
    with pytest.raises(ValueError, match="--option contact_timeconst=log:1,2: write log:FIRST,LAST,COUNT"):
        _select(**MUJOCO, dt=[[1e-3]], option=["contact_timeconst=log:1,2"])


def test_the_size_guard_counts_each_swept_value(monkeypatch):
    pytest.importorskip("mujoco")
    monkeypatch.setattr(selection, "MAX_RUNS", 6)
    with pytest.raises(ValueError, match="the selection is 10 runs, more than 6"):
        _select(**MUJOCO, dt=[[1e-3, 1e-2]], option=["contact_timeconst=log:0.002,0.05,5"])
    with pytest.raises(ValueError, match="--option: the sweeps make 8 option sets, more than 6 runs"):
        _select(**MUJOCO, dt=[[1e-3]], option=["contact_timeconst=lin:0.01,0.02,4", "cone=pyramidal,elliptic"])
    with pytest.raises(ValueError, match="--option contact_timeconst=lin:0.01,0.02,7: 7 values, more than 6"):
        _select(**MUJOCO, dt=[[1e-3]], option=["contact_timeconst=lin:0.01,0.02,7"])
    forced = _select(**MUJOCO, dt=[[1e-3, 1e-2]], option=["contact_timeconst=log:0.002,0.05,5"], force=True)
    assert len(forced.specs) == 10
