"""A store's names that become file names (run keys, case names and versions, the manifest's spec
names) are checked where they are read: a store edited to name a path outside itself
(``x/../../../outside/pwn``) is refused, naming the file the name came from, and nothing is
read or written outside it — by ``run --resume``, ``report`` and ``export``."""

import json
import os
import shutil

import pytest

from dalembert.harness.cli import main
from dalembert.store import Store, StoreError, file_name
from stores import small_store


@pytest.mark.parametrize("name", ["", ".", "..", "a/b", "../x", "a\\b", "a\0b", None, 3])
def test_what_is_not_a_file_name_is_refused_naming_where_it_came_from(name):
    with pytest.raises(StoreError, match=r"^rows/k\.json: key .* is not a file name — the store was edited"):
        file_name(name, "key", "rows/k.json")


@pytest.mark.parametrize("name", ["free_top__reference__rk4__0123456789ab", "a..b", ".hidden", "ref\x1b[2J"])
def test_file_names_pass_as_they_are(name):
    assert file_name(name, "key", "rows/k.json") == name


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    return small_store(tmp_path_factory.mktemp("made") / "store", cases=("pivoted_rod",), integrators=("rk4",),
                       dts=(1e-2,), t_final=0.2)


@pytest.fixture
def store(made, tmp_path):
    """A copy of a real store at tmp_path/store, beside an empty tmp_path/outside."""
    shutil.copytree(made.path, tmp_path / "store")
    (tmp_path / "outside").mkdir()
    return Store.open(tmp_path / "store")


def _edit(path, change):
    with open(path) as fh:
        data = json.load(fh)
    change(data)
    with open(path, "w") as fh:
        json.dump(data, fh)


def _row(store):
    (key,) = store.done_keys()
    return key, os.path.join(store.rows_dir, f"{key}.json")


def test_a_row_key_naming_a_file_outside_is_not_read_by_export(store, tmp_path, capsys):
    key, row = _row(store)
    shutil.copy(os.path.join(store.traj_dir, f"{key}.npz"), tmp_path / "outside" / "stolen.npz")
    _edit(row, lambda r: r.update(key="../../outside/stolen"))
    assert main(["export", store.path, "--all", "--csv", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err
    assert f"{row}: key '../../outside/stolen' is not a file name — the store was edited or damaged" in err
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize("field", ["case", "case_version", "engine", "integrator"])
def test_a_row_s_names_are_checked_when_rows_are_read(store, field):
    _, row = _row(store)
    _edit(row, lambda r: r.update({field: "../../outside/x"}))
    with pytest.raises(StoreError, match=f"{row}: {field} '../../outside/x' is not a file name"):
        store.records()


def test_a_case_record_naming_a_path_outside_makes_no_figure_outside(store, tmp_path, capsys):
    """The report names its figures by the case record's name: ``report_files/02-/../../../outside/x.svg``
    lands outside the store once ``report_files/02-`` exists (the edited store can hold that too)."""
    (case,) = os.listdir(store.cases_dir)
    for n in range(1, 20):
        os.makedirs(os.path.join(store.path, "report_files", f"{n:02d}-"))
    _edit(os.path.join(store.cases_dir, case), lambda c: c.update(name="/../../../outside/x"))
    assert main(["report", store.path]) == 2
    err = capsys.readouterr().err
    assert f"cases/{case}: name '/../../../outside/x' is not a file name" in err
    assert not os.listdir(tmp_path / "outside"), "written outside the store"


def test_a_manifest_integrator_naming_a_path_outside_is_refused_before_resume_runs(tmp_path, capsys):
    out = tmp_path / "store"
    assert main(["run", "--case", "pivoted_rod", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.2", "--jobs", "1", "--quick", "--out", str(out)]) == 0
    store = Store.open(out)
    for key in store.done_keys():  # a matrix to finish ...
        os.unlink(os.path.join(store.rows_dir, f"{key}.json"))
    (tmp_path / "outside").mkdir()  # ... whose key would name rows/pivoted_rod__reference__x/../../../outside
    os.makedirs(os.path.join(store.rows_dir, "pivoted_rod__reference__x"))
    os.makedirs(os.path.join(store.traj_dir, "pivoted_rod__reference__x"))
    _edit(out / "manifest.json", lambda m: m["specs"][0].update(integrator="x/../../../outside/pwn"))
    capsys.readouterr()
    assert main(["run", "--resume", str(out)]) == 2
    err = capsys.readouterr().err
    assert (f"{out / 'manifest.json'}: specs[0].integrator 'x/../../../outside/pwn' is not a file name — the store "
            "was edited or damaged") in err
    assert not os.listdir(tmp_path / "outside"), "written outside the store"


def test_a_run_key_with_a_separator_is_never_written(made, tmp_path):
    from dataclasses import replace

    store = Store(tmp_path / "s").create({"specs": []})
    record = replace(made.records()[0], key="../escaped")
    with pytest.raises(StoreError, match="run key '../escaped' is not a file name"):
        store.write_record(record, b"npz")
    assert sorted(os.listdir(tmp_path)) == ["s"] and not os.listdir(store.rows_dir)
