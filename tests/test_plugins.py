"""Plugin engines (entry point group ``dalembert.adapters``), installed as fake distributions on
``sys.path`` (a ``*.dist-info`` directory with its ``entry_points.txt``; no network, no pip): one that
fails to import is named in a warning and left out while the others list and run; one that reuses a
built-in's name is refused, naming its distribution; a run records the distribution of its adapter."""

import textwrap
import warnings

import pytest

from dalembert.adapters import registry
from dalembert.adapters.registry import PluginWarning, adapter_distribution, adapter_names, get_adapter
from dalembert.harness.cli import main
from dalembert.store import Store

GOOD = """
from dataclasses import dataclass

from dalembert.adapters.base import IntegratorSpec
from dalembert.adapters.reference import ReferenceAdapter


@dataclass(frozen=True)
class OrderedSpec(IntegratorSpec):
    order: int = 4


class FakeAdapter(ReferenceAdapter):
    '''The reference adapter under another name: a plugin that works (its RK4 declaring its order).'''

    integrators = {**ReferenceAdapter.integrators, "rk4": OrderedSpec(True, ("formulation",), "classical RK4", 4)}


class NoReactionsAdapter(FakeAdapter):
    '''The same, reading back no joint reactions (as an engine that cannot report them).'''

    def run(self, prepared):
        from dalembert.adapters.base import Outcome
        from dalembert.trajectory import Trajectory

        out = super().run(prepared)

        def read_back():
            t = out.trajectory
            return Trajectory(t.t, t.bodies, t.joints,
                              {k: v for k, v in t.extras.items() if not k.startswith("reaction_force:")})

        return Outcome(read_back, out.wall_s, out.n_steps, out.n_rhs, out.info)
"""
BROKEN = """
raise ImportError("No module named 'pybullet_engine'")
"""


def _distribution(site, name, version, entry_points, module=None, source=""):
    """A distribution ``name`` ``version`` on ``site`` declaring ``entry_points`` (name -> "module:Class")."""
    info = site / f"{name}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    (info / "entry_points.txt").write_text("[dalembert.adapters]\n" + "".join(f"{k} = {v}\n"
                                                                            for k, v in entry_points.items()))
    if module:
        (site / f"{module}.py").write_text(textwrap.dedent(source))


@pytest.fixture
def site(tmp_path, monkeypatch):
    """Three plugins: ``fake`` that works, ``unimportable`` that cannot be imported (a name no other test
    registers: tests/broken_adapters.py registers a ``broken`` of its own), and one named ``mujoco``."""
    site = tmp_path / "site"
    site.mkdir()
    _distribution(site, "dalembert_fake", "1.2.3", {"fake": "fake_engine:FakeAdapter",
                                                     "noreact": "fake_engine:NoReactionsAdapter"}, "fake_engine", GOOD)
    _distribution(site, "dalembert_broken", "0.3", {"unimportable": "broken_engine:Adapter"}, "broken_engine", BROKEN)
    _distribution(site, "dalembert_shadow", "2.0", {"mujoco": "fake_engine:FakeAdapter"})
    monkeypatch.syspath_prepend(str(site))
    yield site
    for name in ("fake", "noreact", "unimportable"):
        registry._REGISTRY._items.pop(name, None)  # (loaded in this process by the test)


def test_a_broken_plugin_is_named_and_left_out_and_the_others_list(site, capsys):
    with pytest.warns(PluginWarning) as caught:
        names = adapter_names()
    assert "fake" in names and "unimportable" not in names and {"reference", "mujoco"} <= set(names)
    messages = [str(w.message) for w in caught]
    assert any("'unimportable'" in m and "dalembert_broken 0.3" in m and "No module named 'pybullet_engine'" in m
               and "fix or uninstall" in m for m in messages), messages
    assert main(["engines"]) == 0
    captured = capsys.readouterr()
    assert "fake" in captured.out and "reference" in captured.out and "unimportable" not in captured.out
    assert "dalembert: warning: plugin engine 'unimportable'" in captured.err  # one line, the command line's
    assert "(adapter from dalembert_fake 1.2.3)" in next(x for x in captured.out.splitlines() if x.startswith("fake"))
    with pytest.raises(ImportError, match="plugin engine 'unimportable' .*dalembert_broken 0.3.*pybullet_engine"):
        get_adapter("unimportable")


def test_a_plugin_with_a_built_in_name_is_refused_naming_its_distribution(site):
    with pytest.warns(PluginWarning) as caught:
        adapter_names()
    (shadow,) = [str(w.message) for w in caught if "'mujoco'" in str(w.message)]
    assert "dalembert_shadow 2.0" in shadow and "refused" in shadow and "built-in" in shadow
    assert type(get_adapter("mujoco")).__name__ == "MujocoAdapter"  # the name stays the built-in's
    assert adapter_distribution("mujoco")[0] == "dalembert"


def test_a_plain_matrix_keeps_the_plugins_that_load(site):
    from dalembert.harness.matrix import expand

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        specs, skipped = expand(cases=["free_top"], integrators=["rk4"], dts=[1e-2], params={"t_final": 0.5})
    engines = {s.engine for s in specs}
    assert "fake" in engines and "unimportable" not in engines
    assert any(issubclass(w.category, PluginWarning) and "'unimportable'" in str(w.message) for w in caught)


def test_a_plugin_run_records_its_distribution(site, tmp_path):
    assert adapter_distribution("fake") == ("dalembert_fake", "1.2.3")
    out = tmp_path / "r"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PluginWarning)
        assert main(["run", "--case", "free_top", "--engine", "fake", "--integrator", "rk4", "--dt", "1e-2",
                     "--param", "t_final=0.5", "--quick", "--jobs", "1", "--out", str(out)]) == 0
    (record,) = Store(out).records()
    assert record.ok and (record.adapter_distribution, record.adapter_version) == ("dalembert_fake", "1.2.3")
    assert record.integrator_order == 4  # the order its integrator declares, stored for the report's observed order


def test_reactions_an_engine_does_not_report_are_not_measured_not_within(site, tmp_path, capsys):
    """The pivoted rod bounds its reactions: the same motion without them is "not measured", never within."""
    runs = {}
    for engine in ("fake", "noreact"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PluginWarning)
            assert main(["run", "--case", "pivoted_rod", "--engine", engine, "--integrator", "rk4", "--dt", "1e-3",
                         "--param", "t_final=0.5", "--quick", "--jobs", "1", "--out", str(tmp_path / engine),
                         "--strict=tolerance"]) == 0
        (runs[engine],) = Store(tmp_path / engine).records()
    assert runs["fake"].judgement.within_tolerance is True and "reaction_force" in runs["fake"].errors
    j = runs["noreact"].judgement
    assert "reaction_force" not in runs["noreact"].errors
    assert j.not_measured == ("reaction_force",) and j.within_tolerance is None and j.beyond == ()
    assert "not measured, so not within tolerance either" in capsys.readouterr().err
