"""``show-model``: the model an engine builds, with its options; "unsupported" and what would run,
never an empty line."""

import pytest

from dalembert.harness.cli import main


def test_an_option_variant_is_shown(capsys):
    pytest.importorskip("exudyn")
    assert main(["show-model", "free_top", "--engine", "exudyn", "--option", "node=ep"]) == 0
    assert "RotationEulerParameters" in capsys.readouterr().out


def test_an_unsupported_combination_says_so_and_what_runs(capsys):
    pytest.importorskip("exudyn")
    assert main(["show-model", "free_top", "--engine", "exudyn", "--option", "node=ep", "--integrator", "rk44"]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "unsupported: exudyn does not run free_top (rk44, node=ep)" in captured.err
    assert "with node=ep it runs generalized-alpha" in captured.err


def test_an_unknown_option_value_fails_naming_it(capsys):
    pytest.importorskip("exudyn")
    assert main(["show-model", "pivoted_rod", "--engine", "exudyn", "--option", "joints=bogus"]) == 2
    assert "options.joints" in capsys.readouterr().err
