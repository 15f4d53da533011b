"""What an engine refuses is known before the matrix runs: listed once per engine, case and reason in the
manifest and the report, never a run; a refusal only the built model shows stays a run stored ``unsupported``."""

import json

import pytest

from broken_adapters import NoFollower
from dalembert.adapters import adapter_names, check_adapter, register_adapter
from dalembert.adapters.reference import ReferenceAdapter
from dalembert.harness.commands.run import run
from dalembert.harness.execute import QUICK, execute
from dalembert.harness.matrix import expand, split
from dalembert.harness.pool import run_matrix
from dalembert.harness.truths import built_case
from dalembert.refusal import Refusal, group, manifest_refusals
from dalembert.reports.findings import find
from dalembert.reports.sections.common import Report
from dalembert.reports.sections.hazards import hazards
from dalembert.reports.sections.loops import loops
from dalembert.settings import Settings
from dalembert.store import Store

# A short horizon: the runs here are about which runs exist, not about their accuracy.
HORIZON = 0.1  # s: 10 samples of the 1e-2 s sample interval


class BuiltRefusal(ReferenceAdapter):
    """The reference, refusing every scene with a follower force only once its model is built (as MJX's
    ``put_model`` does): nothing is known before the build."""

    BUILT_REASON = "built-refusal: the compiled model has a follower force (known once built)"

    def unsupported(self, scene, settings):
        return self.BUILT_REASON if "load:follower_force" in scene.effects else super().unsupported(scene, settings)

    def unsupported_before_build(self, scene, settings):
        return super().unsupported(scene, settings)


class NoLoops(ReferenceAdapter):
    """The reference without revolute loop closures: the four-bar is refused."""

    effects = ReferenceAdapter.effects - {"loop:revolute"}


class Disagreeing(NoFollower):
    """An adapter whose refusal before the build is not ``unsupported``'s own words: the contract's problem."""

    def unsupported_before_build(self, scene, settings):
        return "some other words" if super().unsupported(scene, settings) else None


for _name, _cls in (("no-follower", NoFollower), ("no-loops", NoLoops), ("built-refusal", BuiltRefusal),
                    ("disagreeing", Disagreeing)):
    if _name not in adapter_names():
        register_adapter(_name, _cls)

REASON = NoFollower().unsupported(built_case("pivoted_rod")[0].scene, Settings("rk4", dt=1e-2))


def _params():
    return {"t_final": HORIZON}


def test_a_refused_run_is_left_out_and_listed_once_per_engine_case_and_reason():
    specs, _ = expand(cases=["pivoted_rod", "free_top"], engines=["no-follower", "reference"],
                      integrators=["rk4", "euler"], dts=[1e-2, 5e-3], params=_params())
    runnable, refused = split(specs)
    assert len(specs) == 16 and len(runnable) == 12  # no-follower's 4 runs of the driven rod are refused
    assert all(not (s.engine == "no-follower" and s.case == "pivoted_rod") for s in runnable)
    assert {s for s, _ in refused} == {s for s in specs if s.engine == "no-follower" and s.case == "pivoted_rod"}
    (refusal,) = group(refused)
    rod = next(s for s in specs if s.case == "pivoted_rod")
    assert (refusal.engine, refusal.case, refusal.params, refusal.case_version) == (
        "no-follower", "pivoted_rod", rod.params, rod.case_version)
    assert refusal.reason == REASON and "load:follower_force" in REASON
    assert refusal.settings == (("rk4", ()), ("euler", ())) and refusal.runs == 4
    assert refusal.text() == f"no-follower cannot run pivoted_rod (t_final=0.1) with euler and rk4: {REASON}"
    assert Refusal.from_json(json.loads(json.dumps(refusal.to_json()))) == refusal


def test_refusals_of_different_reasons_or_cases_stay_apart_and_options_are_named():
    specs, _ = expand(cases=["pivoted_rod", "free_top"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                      params=_params())
    by_case = {s.case: s for s in specs}
    refused = [(by_case["pivoted_rod"], "a"), (by_case["free_top"], "a"), (by_case["pivoted_rod"], "b")]
    assert [(r.case, r.reason, r.runs) for r in group(refused)] == [("pivoted_rod", "a", 1), ("free_top", "a", 1),
                                                                    ("pivoted_rod", "b", 1)]
    with_options = Refusal("e", "c", (), "v", "why", (("rk4", (("node", "ep"),)), ("euler", (("node", "ep"),))), 2)
    assert with_options.what == "euler and rk4 with node=ep"
    mixed = Refusal("e", "c", (), "v", "why", (("rk4", ()), ("rk4", (("node", "ep"),))), 2)
    assert mixed.what == "rk4 and rk4 node=ep"


def test_a_refusal_only_the_built_model_shows_stays_a_run_stored_unsupported():
    specs, _ = expand(cases=["pivoted_rod"], engines=["built-refusal"], integrators=["rk4"], dts=[1e-2],
                      params=_params())
    runnable, refused = split(specs)
    assert runnable == specs and refused == []
    record, npz = execute(runnable[0], QUICK)
    assert record.status == "unsupported" and record.message == BuiltRefusal.BUILT_REASON and npz is None


def test_a_selection_every_run_of_which_is_refused_is_refused_with_the_reason(tmp_path, capsys):
    out = tmp_path / "never"
    with pytest.raises(ValueError, match="the selection holds no run its engines can run: no-follower cannot run "
                                         "pivoted_rod with rk4: .*load:follower_force"):
        run(cases=["pivoted_rod"], engines=["no-follower"], integrators=["rk4"], dts=[1e-2], out=str(out))
    assert not out.exists()  # refused before anything was written


@pytest.fixture(scope="module")
def refusing(tmp_path_factory):
    """Two engines on the driven rod and the four-bar, each refusing one: no-follower the rod, no-loops the four-bar."""
    out = tmp_path_factory.mktemp("refusing") / "store"
    return run(cases=["pivoted_rod", "four_bar"], engines=["no-follower", "no-loops"], integrators=["rk4"],
               dts=[1e-2], params=_params(), quick=True, out=str(out), jobs=1)


def _markdown(store, section):
    """The Markdown of one section of ``store``'s report (unescaped), built as ``build_report`` builds it."""
    records = store.records()
    found = find(store, records)
    rep = Report(store, records, store.manifest(), found, {f: f.case.name for f in found}, {})
    return "\n".join(section(rep).md).replace("\\", "")


def test_the_manifest_lists_the_refusals_and_the_store_holds_only_runs(refusing):
    store = refusing.store
    assert sorted((r.engine, r.case) for r in refusing.records) == [("no-follower", "four_bar"),
                                                                    ("no-loops", "pivoted_rod")]
    assert all(r.status == "ok" for r in refusing.records) and refusing.exit_status == 0
    manifest = store.manifest()
    assert len(manifest["specs"]) == 2
    assert [(r.engine, r.case, r.runs) for r in manifest_refusals(manifest)] == [("no-follower", "pivoted_rod", 1),
                                                                                ("no-loops", "four_bar", 1)]
    assert manifest_refusals(manifest)[0].reason == REASON


def test_the_user_who_named_a_refused_engine_is_told_before_anything_runs(tmp_path, capsys):
    run(cases=["free_top", "pivoted_rod"], engines=["no-follower"], integrators=["rk4"], dts=[1e-2],
        params=_params(), quick=True, out=str(tmp_path / "s"), jobs=1)
    err = capsys.readouterr().err
    refusal = f"no-follower cannot run pivoted_rod (t_final=0.1) with rk4: {REASON}"
    assert err.index(f"note: not run: {refusal}") < err.index("1 runs, 1 to do")
    # the rod has no run, so no section of its own: the report lists its refusal with the hazards
    assert f"- {refusal}" in _markdown(Store.open(str(tmp_path / "s")), hazards)


def test_the_report_lists_a_manifest_refusal_as_it_listed_the_rows(refusing, tmp_path):
    found = {f.case.name: f for f in find(refusing.store)}
    (hazard,) = found["pivoted_rod"].hazards_of("no-follower", "unsupported")
    assert hazard.text == f"no-follower cannot run rk4: {REASON}" and hazard.runs == ()
    assert not found["four_bar"].hazards_of("no-follower", "unsupported")
    assert found["four_bar"].hazards_of("no-loops", "unsupported")
    md = _markdown(refusing.store, hazards)
    assert md.count(REASON) == 1 and f"- {hazard.text}" in md  # once, not once per run
    assert "Not run (refused; the hazards give each reason): no-loops." in _markdown(refusing.store, loops)
    # a store written before refusals were listed: the refused run is a row, and the report says the same
    specs, _ = expand(cases=["pivoted_rod"], engines=["no-follower"], integrators=["rk4"], dts=[1e-2], params=_params())
    old = Store(str(tmp_path / "old")).create({"harness_version": "test", "engines": {"no-follower": "test"},
                                                "specs": [], "machine": {"cores": 2}})
    run_matrix(specs, old, jobs=1, timing=QUICK)
    (row,) = old.records()
    assert row.status == "unsupported"
    (f,) = find(old)
    assert [h.text for h in f.hazards if h.kind == "unsupported"] == [hazard.text]


def test_resume_keeps_the_refusals_and_runs_none_of_them(refusing, capsys):
    again = run(resume=refusing.store.path, jobs=1)
    assert "2 runs, 0 to do" in capsys.readouterr().err
    assert len(again.records) == 2 and manifest_refusals(again.store.manifest()) == manifest_refusals(
        refusing.store.manifest())


def test_a_damaged_refusal_list_is_named():
    with pytest.raises(ValueError, match="manifest.refused: not the refusals dalembert writes"):
        manifest_refusals({"refused": [{"engine": "x"}]})
    assert manifest_refusals({"specs": []}) == ()  # a store written before: its refusals are rows


def test_the_contract_requires_the_refusal_before_the_build_in_unsupported_s_words():
    rod = built_case("pivoted_rod", {"t_final": HORIZON})[0]
    assert check_adapter("no-follower", cases=[rod], integrators=["rk4"]) == []
    (problem,) = check_adapter("disagreeing", cases=[rod], integrators=["rk4"])
    assert "unsupported_before_build gives 'some other words'" in problem
