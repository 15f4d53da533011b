"""Contact maps: a contact case's runs swept over a numeric engine option and the step draw, per engine and
integrator, a heatmap of each stored figure with a cell per run holding that run's value, the cells beyond the
case's bound marked; a store with no option sweep draws none."""

import os

import numpy as np
import pytest
from installed import needs

pytestmark = needs("mujoco")

from dalembert.harness import api  # noqa: E402
from dalembert.reports import contact_figures  # noqa: E402
from dalembert.reports.render import build_report  # noqa: E402
from stores import small_store  # noqa: E402

# Two values of MuJoCo's solref time constant (its default 0.02 and a stiffer 0.005) x two steps: the smallest map.
TIMECONSTS = (0.005, 0.02)
DTS = (1e-3, 1e-2)
FIGURE_ID = 'id="fig-block_on_incline-contact-map-mujoco-implicitfast-contact_timeconst"'


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """The swept store and what ``contact_map`` was given while its report was built."""
    out = str(tmp_path_factory.mktemp("cmap") / "store")
    api.run(cases=["block_on_incline"], engines=["mujoco"], integrators=["implicitfast"], dts=list(DTS),
            options={"contact_timeconst": list(TIMECONSTS)}, out=out, jobs=1, quick=True)
    calls, real = [], contact_figures.contact_map

    def recorded(panels, xs, ys, xlabel, ylabel):
        calls.append(dict(panels=panels, xs=xs, ys=ys, xlabel=xlabel, ylabel=ylabel))
        return real(panels, xs, ys, xlabel, ylabel)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(contact_figures, "contact_map", recorded)
        store = api.load(out)
        build_report(store)
    return store, calls


def test_a_sweep_of_an_option_and_the_step_draws_one_cell_per_run(drawn):
    store, calls = drawn
    records = store.records()
    assert len(records) == len(TIMECONSTS) * len(DTS)
    assert len(calls) == 1
    call = calls[0]
    assert call["xs"] == list(DTS) and call["ys"] == list(TIMECONSTS) and call["ylabel"] == "contact_timeconst"
    panels = {p["title"].split(" ")[0]: p for p in call["panels"]}
    # the figures block_on_incline stores: MuJoCo reports contact forces, so the normal force and the residuals too
    assert set(panels) == {"creep", "penetration", "normal_force_error", "signorini_residual", "cone_residual",
                           "dissipation_residual"}
    case = next(iter({r.case for r in records}))
    assert case == "block_on_incline"
    labels = {label.name: label for label in store.case(case, records[0].case_version).invariants}
    for name, panel in panels.items():
        assert panel["values"].shape == (len(TIMECONSTS), len(DTS))
        for r in records:
            i, j = TIMECONSTS.index(float(r.settings.options["contact_timeconst"])), DTS.index(r.settings.dt)
            assert panel["values"][i, j] == r.drifts[name] * labels[name].scale  # a metric shown in its unit
        assert np.isfinite(panel["values"]).all()
    # the creep bound (1e-4 m/s, cases/block_on_incline.py CREEP_TOL): MuJoCo's soft contact creeps past it
    creep = panels["creep"]
    assert "bound 0.0001" in creep["title"]
    np.testing.assert_array_equal(creep["beyond"], creep["values"] > 1e-4)
    with open(os.path.join(store.path, "report.html")) as fh:
        page = fh.read()
    assert FIGURE_ID in page and "Contact maps: an engine option against the step" in page


def test_a_store_without_an_option_sweep_draws_no_map(tmp_path):
    store = small_store(tmp_path / "flat", cases=("block_on_incline",), engines=("mujoco",),
                        integrators=("implicitfast",), dts=DTS, options={"contact_timeconst": "0.01"})
    build_report(store)
    with open(os.path.join(store.path, "report.html")) as fh:
        page = fh.read()
    assert 'id="fig-block_on_incline-creep"' in page  # the contact section is there ...
    assert "contact-map" not in page and "Contact maps" not in page  # ... without a map
