"""The report of contact cases: each contact case's figures against its closed form (and none for a contact-free
case), metrics shown in their unit and not as drifts, the creep hazard naming the engine and its speed, and the
reason an engine cannot run a contact case."""

import json
import os

import pytest
from installed import needs

pytestmark = needs("mujoco")

from dalembert.reports.findings import CREEP_METRIC, find, speed_text  # noqa: E402
from dalembert.reports.render import build_report  # noqa: E402
from stores import small_store  # noqa: E402

# The reference engine runs the contact-free pendulum and refuses the contact cases (with its reason); MuJoCo runs
# them all with its default (pyramidal) cone, under which the block that must stick creeps (~1.8 mm/s).
ENGINES = ("mujoco", "reference")
CASES = ("block_on_incline", "bouncing_ball", "pendulum")


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    s = small_store(tmp_path_factory.mktemp("contact"), cases=CASES, engines=ENGINES, integrators=("rk4",),
                    dts=(1e-3,), t_final=1.0)
    build_report(s)
    return s


def _page(store):
    with open(os.path.join(store.path, "report.html")) as fh:
        return fh.read()


def _section(md, case):
    """The Markdown of one case's section (from its heading to the next case's): its head in report.md and its
    evidence in report_details.md, together."""
    return "".join(part.split("\n## ")[0] for part in md.split(f"\n## {case}\n")[1:])


def _md(store):
    """report.md, then report_details.md (the evidence report.md links to)."""
    text = ""
    for name in ("report.md", "report_details.md"):
        path = os.path.join(store.path, name)
        if os.path.exists(path):
            with open(path) as fh:
                text += fh.read()
    return text


def test_contact_figures_appear_for_contact_cases_only(store):
    page, md = _page(store), _md(store)
    for case in ("block_on_incline", "bouncing_ball"):
        assert f'id="fig-{case}-contact"' in page
        assert "### Contact against the closed form" in _section(md, case)
    assert 'id="fig-block_on_incline-creep"' in page  # the case that measures creep: its log-scale bars
    assert 'id="fig-bouncing_ball-creep"' not in page
    assert "apex height per bounce" in page
    assert 'id="fig-pendulum-contact"' not in page
    assert "Contact against the closed form" not in _section(md, "pendulum")


def test_the_events_table_reads_the_closed_form_and_each_run(store):
    md = _section(_md(store), "bouncing_ball")
    case = next(f.case for f in find(store) if f.case.name == "bouncing_ball")
    e, h = case.params["restitution"], case.params["height"]
    (truth,) = [line for line in md.splitlines() if line.startswith("| closed form |")]
    # the closed form's first apex e^2 h (the only one within this 1-s horizon), read off its stored samples (exact
    # for the parabolic flight)
    assert truth == f"| closed form | {e ** 2 * h:.4g} |"
    assert any(line.startswith("| mujoco rk4 dt=0.001 |") for line in md.splitlines())


def test_a_metric_is_shown_in_its_unit_not_as_a_drift(store):
    md = _section(_md(store), "block_on_incline")
    # the every-run table's column (one run: folded into its "In every row" note); the stored verdict's reason
    # is the harness's own text ("creep drift 1.80e-03 > 0.0001"), not a column's label
    assert "creep (m/s) " in md
    assert "creep drift (" not in md and "relative to 1 m/s" not in md
    # the metrics table: its bound in its unit (the case's CREEP_TOL, 1e-4 m/s, over a scale of 1 m/s)
    assert "| creep |" in md and "| m/s | 0.0001 m/s |" in md
    creep = next(r for r in store.records() if r.case == "block_on_incline" and r.engine == "mujoco")
    assert f"{creep.drifts[CREEP_METRIC]:.2e}" in md  # the stored value, shown as the figure in m/s (scale 1 m/s)
    # the store says which declared figure is a metric; a contact-free case's record is as it was
    with open(os.path.join(store.path, "cases", f"block_on_incline__{creep.case_version}.json")) as fh:
        assert {i["name"]: i.get("kind") for i in json.load(fh)["invariants"]}[CREEP_METRIC] == "metric"


def test_the_creep_hazard_names_the_engine_and_the_speed(store):
    found = next(f for f in find(store) if f.case.name == "block_on_incline")
    (hazard,) = [h for h in found.hazards if h.kind == "creep"]
    run = next(r for r in found.runs if r.engine == "mujoco")
    speed = run.drifts[CREEP_METRIC]  # m/s (the metric's scale is 1 m/s)
    assert speed > found.case.tolerances[CREEP_METRIC].value  # MuJoCo's default cone creeps beyond the bound
    assert hazard.engine == "mujoco" and hazard.text.startswith("mujoco: ")
    assert speed_text(speed) in hazard.text and "mm/s" in hazard.text
    assert "Creeps where it must stick" in _page(store) and hazard.text in _md(store).replace("\\", "")


def test_an_engine_that_cannot_run_a_contact_case_says_why(store):
    refused = [r for r in store.records() if r.case == "block_on_incline" and r.status == "unsupported"]
    assert refused, "the reference engine refuses contact scenes"
    md = _md(store).replace("\\", "")
    assert all(r.message in md for r in refused)


def test_speed_text_picks_the_unit_a_creep_reads_in():
    assert speed_text(0.0018) == "1.8 mm/s"
    assert speed_text(8.75e-4) == "875 um/s"
    assert speed_text(2.5) == "2.5 m/s"
    assert speed_text(5e-12) == "0.005 nm/s"


def test_an_engine_that_cannot_run_contact_says_why_in_the_report(tmp_path):
    """Pinocchio has no contact time-stepper mapped: its refusal, with the reason, is in the report."""
    s = small_store(tmp_path, cases=("block_on_incline",), engines=("pinocchio",), integrators=("rk4",),
                    dts=(1e-3,), t_final=0.2)
    build_report(s)
    (r,) = s.records()
    assert r.status == "unsupported" and "contact" in r.message
    assert f"pinocchio cannot run rk4: {r.message}" in _md(s).replace("\\", "")


def test_what_accuracy_costs_ranks_a_contact_case_by_its_headline_figure(store):
    found = {f.case.name: f for f in find(store)}
    block, ball, pendulum = found["block_on_incline"], found["bouncing_ball"], found["pendulum"]
    # the headline survives the store (CaseRecord JSON) and ranks the engines in its unit
    assert (block.ranked, block.ranked_unit) == ("creep", "m/s") and (ball.ranked, ball.ranked_unit) == ("apex_error", "m")
    (mujoco,) = [e for e in block.engines if e.engine == "mujoco"]
    run = mujoco.best.run
    assert mujoco.best.error == run.drifts["creep"]  # creep's scale is 1 m/s: the stored value in m/s
    assert block.ranked_tolerance == block.case.tolerances["creep"].value
    (mujoco,) = [e for e in ball.engines if e.engine == "mujoco"]
    height = ball.case.params["height"]  # apex_error is stored over the drop height
    assert mujoco.best.error == pytest.approx(mujoco.best.run.drifts["apex_error"] * height, rel=1e-15)
    assert block.sentences[0].startswith("Headline figure: creep (m/s), mean speed of the box")
    # a contact-free case ranks by its error against the truth, as before
    assert pendulum.headline is None and pendulum.ranked == pendulum.quantity
    assert pendulum.sentences[0].startswith(f"Headline error: {pendulum.quantity}")
    md = _section(_md(store), "block_on_incline")
    costs = md.split("### What accuracy costs")[1].split("\n### ")[0]
    assert "best (m/s)" in costs and "creep against stepping time" in costs


def test_the_contact_forces_table_shows_each_runs_figures_and_not_measured_where_none(tmp_path):
    from broken_adapters import ForceBlind

    from dalembert.adapters.registry import adapter_names, register_adapter

    if "force-blind" not in adapter_names():
        register_adapter("force-blind", ForceBlind)  # MuJoCo without its contact forces
    s = small_store(tmp_path / "forces", cases=("block_on_incline",), engines=("mujoco", "force-blind"),
                    integrators=("euler",), dts=(1e-3,), t_final=0.5)
    build_report(s)
    md = _section(_md(s), "block_on_incline")
    table = md.split("ContactBench's residuals")[1].split("\n\n")[1]
    rows = {line.split("|")[1].strip().split(" ")[0]: line for line in table.splitlines() if line.startswith("| ")}
    assert "not measured" in rows["force-blind"] and "not measured" not in rows["mujoco"]
    assert " N" in rows["mujoco"] and " W" in rows["mujoco"]  # the normal-force error in N, the residuals in W
    (blind,) = [r for r in s.records() if r.engine == "force-blind"]
    # not measured is never within: MuJoCo's default creep is beyond its bound, so the run is not within (False)
    assert "normal_force_error" not in blind.drifts and blind.judgement.within_tolerance is False
