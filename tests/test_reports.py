"""Reports: built from a small store made here; checked as files and in a real browser."""

import html
import json
import os
import re
import shutil
import subprocess

import pandas as pd
import pytest

from dalembert.store import Store
from dalembert.reports.render import build_report
from stores import small_store

# Screenshots go where DALEMBERT_ARTIFACTS says (CI may keep them), else into the test's own
# temporary directory: a test writes nothing into the checkout.
ARTIFACTS = os.environ.get("DALEMBERT_ARTIFACTS")


@pytest.fixture(scope="session")
def store(tmp_path_factory):
    """A small matrix of two cases and its report. Session-scoped, though only this module uses it: the long test
    below runs first (tests/conftest.py), apart from the others, and a module fixture would be built again for them
    after the modules in between (a matrix and a report: seconds)."""
    engines = ("reference", "mujoco") if _importable("mujoco") else ("reference",)
    s = small_store(tmp_path_factory.mktemp("store"), engines=engines)
    build_report(s)
    return s


def _importable(name):
    import importlib.util

    return importlib.util.find_spec(name) is not None


def _section(md, case):
    """The Markdown of one case's section (from its heading to the next case's): its head in report.md and its
    evidence in report_details.md (``_md``), together."""
    return "".join(part.split("\n## ")[0] for part in md.split(f"\n## {case}\n")[1:])


def _md(path):
    """report.md, then report_details.md (the evidence report.md links to), of the report in ``path``."""
    return "".join(open(os.path.join(path, name)).read() for name in ("report.md", "report_details.md")
                   if os.path.exists(os.path.join(path, name)))


def _headline(case):
    return "joint" if case == "pivoted_rod" else "orientation"


def test_report_files_and_values_equal_the_store(store):
    for name in ("report.html", "report.md", "summary.csv"):
        assert os.path.getsize(os.path.join(store.path, name)) > 0
    records = store.records()
    summary = pd.read_csv(os.path.join(store.path, "summary.csv"))
    for _, s in summary.iterrows():
        mine = [r.max_error(_headline(s.case)) for r in records if r.case == s.case and r.engine == s.engine]
        assert s.best_error == min(mine)  # full precision in the CSV
    md = _md(store.path)
    for r in records:  # every stored headline error appears as shown (3 significant digits) in its case's runs
        assert f"{r.max_error(_headline(r.case)):.2e}" in _section(md, r.case)
    figures = re.findall(r"!\[[^\]]*\]\((report_files/[^)]+)\)", md)
    assert figures and all(os.path.exists(os.path.join(store.path, f)) for f in figures)


def test_report_md_links_each_case_s_evidence_in_report_details(store):
    """report.md has the HTML's economy: a case's folded evidence is in report_details.md, one link each in its
    place, every link to an anchor there (every number reachable, ``test_report_files_and_values_equal_the_store``)."""
    main = open(os.path.join(store.path, "report.md")).read()
    details = open(os.path.join(store.path, "report_details.md")).read()
    links = re.findall(r"\(report_details\.md#(detail-\d+)\)", main)
    assert links and len(set(links)) == len(links)
    assert all(f'<a id="{a}"></a>' in details for a in links)
    assert "### Every run" not in main and "### Every run" in details
    for case in ("free_top", "pivoted_rod"):  # each case's head stays in report.md, its evidence under its name
        assert f"\n## {case}\n" in main and f"\n## {case}\n" in details


def test_energy_drift_rates_are_shown_as_stored(store):
    """The drift-rate table: every successful run's stored slope, signed, per engine + integrator
    and step (explicit Euler's secular drift and RK4's near-zero one side by side)."""
    md = _md(store.path)
    section = _section(md, "free_top").split("### Energy drift rate")[1].split("###")[0]
    top = [r for r in store.records() if r.case == "free_top" and r.ok and r.engine == "reference"]
    assert len(top) == 4
    for r in top:
        line = next(x for x in section.splitlines() if x.startswith(f"| {r.engine} {r.settings.integrator} |"))
        assert f"{r.drift_rates['energy']:+.2e} /s" in line
    euler, rk4 = (max(abs(r.drift_rates["energy"]) for r in top if r.settings.integrator == k) for k in ("euler", "rk4"))
    assert euler > 1e3 * rk4


def test_report_is_self_contained(store):
    page = open(os.path.join(store.path, "report.html")).read()
    # no resource is fetched from anywhere: every src/href is local (anchors) or inline
    refs = re.findall(r'(?:src|href)="([^"]*)"', page)
    assert refs and all(r.startswith(("#", "data:")) for r in refs), [r for r in refs if not r.startswith("#")]
    assert "<link" not in page and "@import" not in page


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


# What the browser test photographs: the findings, then one of each kind of figure (element ids in
# report.html; the first case's figures), each with the page opened at a link to it (its folds open).
# Each shot runs from its element to the next one listed in data-at, or to the given one (the findings:
# the summary figure, table and sentences, up to the hazards).
SHOTS = {"summary": ("fig-summary", "findings", "hazards"), "work-precision": ("fig-{case}-wp", "fig-{case}-wp", None),
         "stability": ("fig-{case}-stability", "fig-{case}-stability", None),
         "time": ("fig-{case}-time", "fig-{case}-time", None)}
WIDTH = 1400  # px: a laptop's browser window; nothing may be wider
# A screen: a 1400 px wide laptop window, 900 px of it the page; the default report must fit in MAX_SCREENS of
# them with every fold closed (the "under ~8 screens": what a reader scrolls through before choosing).
SCREEN = 900
MAX_SCREENS = 8


def test_report_renders_in_a_real_browser(store, tmp_path):
    """Every figure drawn, no console error, nothing fetched, nothing wider than 1400 px (with every
    <details> open), the page no taller than ``MAX_SCREENS`` screens with every fold closed, and screenshots of
    the first screen, the findings, a work-precision figure, a stability figure and a time plot. DALEMBERT_REPORT_STORE may name a default-matrix store to photograph instead of
    this module's small one (it is copied; the copy gets the report)."""
    browser = _chromium()
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("CI must install Debian's chromium (see .ci/run)")
        pytest.skip("chromium not installed (apt-get install chromium); CI installs it")
    from PIL import Image

    source = store
    if os.environ.get("DALEMBERT_REPORT_STORE"):
        shutil.copytree(os.environ["DALEMBERT_REPORT_STORE"], tmp_path / "big")
        source = Store.open(tmp_path / "big")
        build_report(source)
    url = "file://" + os.path.join(source.path, "report.html")
    flags = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
             f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
             "--virtual-time-budget=5000"]
    dom = subprocess.run(flags + [f"--window-size={WIDTH},2000", "--dump-dom", url], capture_output=True, text=True,
                         timeout=120)
    drawn = re.search(r'data-figures="(\d+)/(\d+)"', dom.stdout)
    assert drawn, "the report's self-check did not run"
    assert int(drawn.group(2)) > 0 and drawn.group(1) == drawn.group(2), f"figures drawn: {drawn.group(0)}"
    assert re.search(r'data-overflow="([^"]*)"', dom.stdout).group(1) == "none", "wider than the window"
    console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line]
    assert console == [], console
    assert not re.search(r"net::ERR_|Failed to load resource", dom.stderr)
    folded = int(re.search(r'data-height="(\d+)"', dom.stdout).group(1))
    assert folded <= MAX_SCREENS * SCREEN, f"{folded} px folded: more than {MAX_SCREENS} screens of {SCREEN} px"
    artifacts = ARTIFACTS or str(tmp_path)
    os.makedirs(artifacts, exist_ok=True)
    first = os.path.join(artifacts, "report-first-screen.png")  # what a reader sees on opening it
    subprocess.run(flags + [f"--window-size={WIDTH},{SCREEN}", f"--screenshot={first}", url], capture_output=True,
                   timeout=120)
    assert os.path.getsize(first) > 5_000
    case = sorted(r.case for r in source.records())[0]
    for name, (target, start, end) in SHOTS.items():
        # the page as a link to the figure leaves it: the folds around it open (report.js), the rest closed
        url_at = url + "#" + target.format(case=case)
        dom = subprocess.run(flags + [f"--window-size={WIDTH},2000", "--dump-dom", url_at], capture_output=True,
                             text=True, timeout=120)
        at = json.loads(html.unescape(re.search(r'data-at="([^"]*)"', dom.stdout).group(1)))
        height = int(re.search(r'data-height="(\d+)"', dom.stdout).group(1))
        assert height > folded  # the fold held the figure
        page = os.path.join(artifacts, f"report-page-{name}.png")
        subprocess.run(flags + [f"--window-size={WIDTH},{height}", f"--screenshot={page}", url_at],
                       capture_output=True, timeout=120)
        full = Image.open(page)
        assert full.size[0] == WIDTH
        top = at[start.format(case=case)]
        tops = sorted(at.values())
        bottom = min([at[end] if end else min([t for t in tops if t > top], default=height), height, top + 1800])
        shot = os.path.join(artifacts, f"report-{name}.png")
        full.crop((0, max(0, top - 10), WIDTH, bottom)).save(shot)
        os.remove(page)
        assert os.path.getsize(shot) > 5_000


@pytest.mark.long
def test_report_reads_only_the_store(store, tmp_path):
    """With the cases, the reference solver and the engines unimportable, the report still
    builds from the store alone — through the command line, as a user runs it — and shows the
    verdicts as stored (a tolerance changed in code later cannot re-judge them)."""
    import sys

    out = tmp_path / "copy"
    shutil.copytree(store.path, out)
    # one stored verdict that the tolerances in code would not give: the report must show it as stored
    key = next(r.key for r in store.records() if r.judgement.verdict == "stable")
    row = json.load(open(out / "rows" / f"{key}.json"))
    row["verdict"], row["verdict_reason"] = "drifts", "as judged when it ran"
    json.dump(row, open(out / "rows" / f"{key}.json", "w"))
    script = ("import sys\n"
              "for name in ('dalembert.cases', 'dalembert.reference', 'dalembert.adapters', 'mujoco', 'pinocchio', "
              "'exudyn'):\n    sys.modules[name] = None\n"
              "from dalembert.harness.cli import main\n"
              f"raise SystemExit(main(['report', {str(out)!r}]))\n")
    ran = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert ran.returncode == 0, ran.stderr[-2000:]
    md = _md(out)
    for r in Store(out).records():
        assert r.judgement.verdict in md
    assert "as judged when it ran" in md


def test_a_store_of_another_schema_is_refused_clearly(store, tmp_path, capsys):
    from dalembert.harness.cli import main

    other = tmp_path / "other"
    shutil.copytree(store.path, other)
    manifest = json.load(open(other / "manifest.json"))
    manifest["schema_version"] = 99
    json.dump(manifest, open(other / "manifest.json", "w"))
    assert main(["report", str(other)]) == 2
    err = capsys.readouterr().err
    assert "schema 99" in err and str(other) in err
