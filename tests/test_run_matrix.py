"""The run matrix: failures are data, timeouts stop, interrupted runs resume, Dask matches local."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from dalembert.adapters import adapter_names, check_adapter, register_adapter
from broken_adapters import Broken, Loaded, NoFollower, SlowReadBack, Threads, Unloadable
from engine_runs import installed, real_engines
from dalembert.harness.execute import QUICK, Timing, execute
from dalembert.harness.matrix import RunSpec, expand
from dalembert.harness.pool import run_matrix
from dalembert.record import RunRecord
from dalembert.store import Store

# The kernel kills a worker when its parent dies; this only bounds how long a busy machine may
# take to schedule that, and is far below CI's own limit.
ORPHAN_GRACE_S = 60.0
# Every case's first CONTRACT_SAMPLES sample intervals (its own horizon where that is shorter): the contract is about
# behaviour (exact sampling, repeatability, the audit), which ten samples show as well as a thousand; the step
# count, not the time, is what a run costs (the Andrews squeezer is sampled every 1 ms at ~3 ms per evaluation:
# 10 ms of it, where 0.2 s of every case took its own 30 ms, a third of the reference's contract).
CONTRACT_SAMPLES = 10
# The JIT-compiled engines' horizon, in seconds: their compiled rollout's shape holds the sample count, and 0.2 s
# (20 samples at 1e-2) is the programs the other tests named below compile too, shared through JAX's caches.
CONTRACT_HORIZON = 0.2
# Engines that compile each model and integrator (JAX's JIT: 3-15 s each on 2 idle cores, twice that on a busy
# one; 54 compilations for every case and integrator): their contract runs every integrator on ``JIT_TREE_CASE``
# (a jointed tree with a load: MJX's actuator path), and one integrator on the smallest case of each other kind of
# model their own code treats apart — a free body, and loop closures with spring-dampers (equality constraints and
# tendons on the device, together). The model build and read-back are MuJoCo's, whose contract runs every case.
# 5 compilations, three of them programs other tests run too (``test_mjx``'s float32 rod, the divergence and parity
# tests' top, the reliability test's rod), where the contract took 7 programs on the largest cases before.
# MuJoCo Warp likewise (Warp compiles kernels per model structure, and each step is ms of Python launches: its
# contract over every case took 627 s on 2 busy cores).
# Newton likewise (Warp kernels per model structure and solver; VBD's steps cost ~10-30 ms of Python each).
JIT_COMPILED = {"mjx": "euler", "mujoco_warp": "euler", "newton": "featherstone"}
JIT_TREE_CASE = "pivoted_rod"


ENGINES = real_engines()  # not the test-only adapters below, nor those another test module registered
for _name, _cls in (("broken", Broken), ("no-follower", NoFollower), ("threads", Threads),
                    ("slow-read-back", SlowReadBack), ("loaded", Loaded), ("unloadable", Unloadable)):
    if _name not in adapter_names():
        register_adapter(_name, _cls)


@pytest.mark.long
@pytest.mark.parametrize("engine", ENGINES)
def test_every_adapter_meets_the_contract(engine):
    from dalembert.case import load_cases

    if not installed(engine):  # asked here, not while collecting: asking imports the engine (seconds, per worker)
        pytest.skip(f"{engine} is not installed (an optional engine outside dalembert[all])")

    # every registered case, on a short horizon: the contract is about behaviour (sampling,
    # repeatability, the audit), not accuracy, and the 27-body cases cost seconds per second in Python;
    # a case whose own horizon is shorter keeps it
    def horizon(case):
        return CONTRACT_HORIZON if engine in JIT_COMPILED else CONTRACT_SAMPLES * float(case.times[1] - case.times[0])

    cases = [f(t_final=min(horizon(f()), f.params["t_final"])) for _, f in load_cases().items()]
    if engine in JIT_COMPILED:
        kinds = {}  # (loops with springs, a free joint) -> the case with the fewest bodies
        for c in sorted(cases, key=lambda c: (len(c.scene.bodies), c.name)):
            kinds.setdefault((bool(c.scene.loops and c.scene.springs), any(j.kind == "free" for j in c.scene.joints)), c)
        tree = next(c for c in cases if c.name == JIT_TREE_CASE)
        assert check_adapter(engine, cases=[tree]) == []
        assert check_adapter(engine, cases=[kinds[False, True], kinds[True, False]],
                             integrators=(JIT_COMPILED[engine],)) == []
        return
    assert check_adapter(engine, cases=cases) == []


@pytest.mark.parametrize("engine,integrator", [("reference", "rkmk4"), ("reference", "rk4"), ("pinocchio", "rk4"),
                                               ("pinocchio", "euler"), ("mujoco", "rk4")])
def test_a_blow_up_is_nan_not_an_exception(engine, integrator):
    """500 rad/s at dt = 1e-2 (5 rad per step): the state blows up; the run returns NaN from there."""
    from dalembert.adapters import get_adapter
    from dalembert import Settings, make_case

    case = make_case("free_top_fast_spin", spin=500.0, t_final=2.0)
    adapter = get_adapter(engine)
    out = adapter.run(adapter.prepare(case.scene, case.times, Settings(integrator, dt=1e-2)))
    assert not out.trajectory.is_finite()


# The per-run limit for the runs that end: each (a worker's first includes its engine's import and the case's
# build, ~1 s idle) must finish inside it on a machine loaded many times over (5 s timed out a first run at load
# 20 on 2 cores); none of them waits for it.
RUN_LIMIT_S = 20.0
# The per-run limit of the hanging run, which it always reaches, whatever the load: the wall time it costs.
HANG_LIMIT_S = 1.0


def test_failures_are_stored_not_raised(tmp_path):
    """A run that raises, one that diverges, one that hangs and a good one: each stored with its status and
    verdict, none raised. The hang runs with its own short limit once the others are stored (``run_matrix`` on
    the whole matrix again, as ``--resume``): a limit the others could also meet would make it as long as theirs
    must be on a loaded machine."""
    specs, _ = expand(cases=["pivoted_rod"], engines=["broken"], dts=[1e-2])
    store = Store(tmp_path).create({"specs": [s.to_json() for s in specs]})
    run_matrix([s for s in specs if s.settings.integrator != "hangs"], store, jobs=2, timeout=RUN_LIMIT_S,
               timing=QUICK)
    assert len(store.done_keys()) == 3
    run_matrix(specs, store, jobs=2, timeout=HANG_LIMIT_S, timing=QUICK)
    runs = {r.settings.integrator: r for r in store.records()}
    assert runs["raises"].status == "failed" and "exploded on purpose" in runs["raises"].message
    assert runs["nan"].status == "diverged" and "t = 1 s" in runs["nan"].message
    assert runs["hangs"].status == "timeout" and f"{HANG_LIMIT_S:g} s" in runs["hangs"].message
    assert runs["rk4"].status == "ok" and runs["rk4"].judgement.within_tolerance
    # the verdict is judged when the run ends and stored with it
    assert [runs[k].judgement.verdict for k in ("raises", "nan", "hangs", "rk4")] == ["failed", "diverged", "timeout", "stable"]
    table = store.write_table()
    assert len(table) == 4 and (tmp_path / "runs.parquet").exists()
    assert {"schema_version", "verdict", "verdict_reason"} <= set(table.columns)


def test_unsupported_effect_is_a_stored_result():
    (spec,), _ = expand(cases=["pivoted_rod"], engines=["no-follower"], integrators=["rk4"], dts=[1e-2])
    record, npz = execute(spec, QUICK)
    assert record.status == "unsupported" and "load:follower_force" in record.message and npz is None
    assert record.judgement.verdict == "unsupported" and record.judgement.reason == record.message


def test_the_read_back_is_timed_once_and_apart_from_the_stepping():
    """A read-back that sleeps 0.5 s: the record's ``readback_s`` holds it once (not once per timed
    repeat: that would be 4 x 0.5 s), the stepping times do not hold it (20 RK4 steps of a rod take ~1 ms),
    the worker's time holds both."""
    (spec,), _ = expand(cases=["pivoted_rod"], engines=["slow-read-back"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 0.2})
    record, _ = execute(spec, Timing(min_repeats=3, min_total_s=0.0, max_repeats=3))
    cost, pause = record.cost, SlowReadBack.PAUSE_S
    assert record.status == "ok" and cost.repeats == 3
    assert pause <= cost.readback_s < 4 * pause
    assert cost.wall_s_max < pause
    assert cost.worker_s >= cost.build_s + cost.stepping_total_s + cost.readback_s


def test_workers_load_their_engines_before_their_first_run(tmp_path):
    """Each worker loads the matrix's engines (``Adapter.load``) before it runs anything, so no run's time holds an
    engine's import; an engine whose load fails still runs (its runs carry their own errors)."""
    specs, _ = expand(cases=["pivoted_rod"], engines=["loaded", "unloadable"], integrators=["rk4"], dts=[1e-2],
                      params={"t_final": 0.2})
    store = Store(tmp_path).create({})
    run_matrix(specs, store, jobs=2, timing=QUICK)
    records = {r.engine: r for r in store.records()}
    assert records["loaded"].status == "ok" and records["loaded"].audit["loaded_before_first_run"] == 1
    assert records["unloadable"].status == "ok"


def test_stored_row_and_trajectory_round_trip(tmp_path):
    (spec,), _ = expand(cases=["free_top"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 1.0})
    store = Store(tmp_path).create({})
    run_matrix([spec], store, jobs=1, timing=QUICK)
    (row,) = store.rows()
    record = RunRecord.from_row(row)
    assert record.key == spec.key and record.status == "ok" and record.cost.repeats == 1
    assert RunRecord.from_row(json.loads(json.dumps(record.to_row()))).to_row() == row  # the row round-trips
    traj = store.trajectory(spec.key)
    assert traj.t[-1] == 1.0 and "top" in traj.bodies
    from dalembert.case import make_case
    from dalembert.errors import trajectory_errors

    case = make_case("free_top", t_final=1.0)
    assert trajectory_errors(traj, case.exact(case.times))["orientation"][0] == record.max_error("orientation")
    assert RunSpec.from_json(json.loads(json.dumps(spec.to_json()))) == spec


def _cli(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "dalembert.harness.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, **kw)


@pytest.mark.long
def test_interrupted_run_resumes_to_the_same_store(tmp_path):
    """Killed (SIGKILL) after two runs: ``--resume`` redoes nothing stored, finishes the rest with the
    timing policy the matrix started with (``--quick``: one timed repeat), and ends with the rows of an
    uninterrupted matrix."""
    selection = ["--case", "free_top", "--case", "pivoted_rod", "--engine", "reference", "--dt", "1e-2,5e-3",
                 "--rtol", "1e-6", "--param", "t_final=1", "--jobs", "1", "--quick"]
    from dalembert.harness.cli import main

    full = tmp_path / "full"  # the uninterrupted matrix: in this process (what is killed is the one below)
    assert main(["run", *selection, "--out", str(full)]) == 0
    cut = tmp_path / "cut"
    proc = _cli("run", *selection, "--out", str(cut))
    store = Store(cut)
    while len(store.done_keys()) < 2 and proc.poll() is None:  # no deadline: a busy machine is slow, not wrong
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_before = len(store.done_keys())
    assert 2 <= n_before < len(Store(full).done_keys())
    before = {r.key: r for r in store.records()}
    assert _cli("run", "--resume", str(cut)).wait() == 0
    after = {r.key: r for r in store.records()}
    reference = {r.key: r for r in Store(full).records()}
    assert set(after) == set(reference)  # same rows, none missing, no duplicates
    for key, row in before.items():  # nothing finished was redone
        assert after[key].cost == row.cost
    for key, row in reference.items():  # deterministic numbers
        assert after[key].status == row.status
        assert after[key].errors == row.errors
    assert {r.cost.repeats for r in after.values() if r.status == "ok"} == {1}


@pytest.mark.leaves_threads  # the in-process client leaves distributed's offload thread behind
def test_dask_cluster_gives_the_same_rows(tmp_path, monkeypatch):
    """The same rows as a local pool; each task's BLAS and OpenMP pools get its share of its host's cores (two
    single-threaded workers on one host: half of them each, as a local pool of two), whatever the workers
    inherited."""
    distributed = pytest.importorskip("distributed")
    from dalembert.harness.dask import run_matrix_dask
    from dalembert.harness.threads import VARIABLES

    for var in VARIABLES:
        monkeypatch.setenv(var, "7")

    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4", "dop853"], dts=[1e-2],
                      rtols=[1e-6], params={"t_final": 1.0})
    local = Store(tmp_path / "local").create({})
    run_matrix(specs, local, jobs=1, timing=QUICK)
    remote = Store(tmp_path / "dask").create({})
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                                  processes=True) as cluster, distributed.Client(cluster) as client:
        run_matrix_dask(specs, remote, client, timing=QUICK)
    assert [r.provenance["threads"] for r in remote.records()] == [max(1, (os.cpu_count() or 1) // 2)] * len(specs)
    # everything but where and how long it ran
    drop = {"wall_s_median", "wall_s_min", "wall_s_max", "wall_s_repeats", "overhead_s", "readback_s", "build_s", "worker_s",
            "stepping_total_s", "provenance", "load_start", "load_end"}
    strip = lambda rows: [{k: v for k, v in r.items() if k not in drop} for r in rows]  # noqa: E731
    assert strip(local.rows()) == strip(remote.rows())
    for key in local.done_keys():
        a, b = local.trajectory(key), remote.trajectory(key)
        assert np.array_equal(a.bodies["rod"].quaternion, b.bodies["rod"].quaternion)


@pytest.mark.parametrize("args,words", [
    (["--case", "free_tops"], "did you mean 'free_top'"),
    (["--engine", "mujocoo"], "unknown engine"),
    (["--integrator", "rk5", "--engine", "reference"], "did you mean 'rk4'"),
    (["--dt=-1e-3"], "--dt: must be positive"),
    (["--rtol", "0"], "--rtol: must be positive"),
    (["--rtol=-1e-6,1e-3"], "--rtol: must be positive"),
    (["--dt", "3e-3", "--engine", "reference", "--integrator", "rk4"], "does not divide"),
    (["--tag", "fre"], "did you mean 'free'"),
    (["--out", "/proc/forbidden"], "--out"),
])
def test_bad_command_lines_fail_fast_and_write_nothing(args, words, tmp_path, capsys, monkeypatch):
    from dalembert.harness.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["run", *args]) == 2
    assert words in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "results")


def test_a_diverged_run_is_a_finding_unless_strict(tmp_path):
    """Tait-Bryan nodes pass their singularity in the first intermediate-axis flip (t = 0.35 s)."""
    pytest.importorskip("exudyn")
    from dalembert.harness.cli import main

    args = ["run", "--case", "free_top_intermediate", "--engine", "exudyn", "--integrator", "rk44",
            "--option", "node=rxyz", "--dt", "1e-2", "--param", "t_final=1", "--jobs", "1"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert main([*args, "--out", str(tmp_path / "b"), "--strict"]) == 1
    assert [r.status for r in Store(tmp_path / "a").records()] == ["diverged"]


def test_export_writes_a_stored_trajectory(tmp_path, capsys):
    import pandas as pd

    from dalembert.harness.cli import main

    out = tmp_path / "r"
    assert main(["run", "--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.5", "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    assert "## free_top" in (out / "report.md").read_text() and (out / "report.html").exists()
    assert main(["export", str(out), "--case", "free_top", "--engine", "reference", "--integrator", "rk4",
                 "--csv", str(tmp_path / "x.csv")]) == 0
    df = pd.read_csv(tmp_path / "x.csv")  # long format: a row per sample and item (dalembert.reports.export)
    assert np.array_equal(df[df.kind == "body"].t.to_numpy(), np.linspace(0, 0.5, 51))


def test_resume_refuses_a_case_that_changed(tmp_path, capsys):
    """Finishing a store after a case's code changed would mix two versions of the case: refused,
    naming the case; a store written with another schema is refused too."""
    from dalembert.harness.cli import main

    out = tmp_path / "r"
    assert main(["run", "--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.5", "--out", str(out)]) == 0
    store = Store(out)
    assert {"schema_version", "verdict", "verdict_reason"} <= set(store.table().columns)
    assert store.schema_version() == store.rows()[0]["schema_version"] == 4
    manifest = store.manifest()
    manifest["specs"][0]["case_version"] = "0123456789ab"  # as if the case's code had changed since
    store.write_manifest(manifest)
    assert main(["run", "--resume", str(out)]) == 2
    err = capsys.readouterr().err
    assert "case 'free_top'" in err and "0123456789ab" in err
    manifest["schema_version"] = 1
    store.write_manifest(manifest)
    assert main(["run", "--resume", str(out)]) == 2
    assert "schema 1" in capsys.readouterr().err


def test_the_store_carries_the_case_as_run(tmp_path):
    """Scene, parameters, tolerances with reasons, conserved quantities and the truth, read back
    equal to the case the code makes."""
    from dalembert.case import make_case

    (spec,), _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 1.0})
    store = Store(tmp_path).create({})
    run_matrix([spec], store, jobs=1, timing=QUICK)
    case = make_case("pivoted_rod", t_final=1.0)
    stored = store.case("pivoted_rod", case.version)
    assert stored.scene == case.scene and stored.params == case.params
    assert stored.tolerances == case.tolerances and stored.conserved == case.conserved
    assert stored.sample_times == case.sample_times and stored.truth == "closed form"
    truth = store.truth("pivoted_rod", case.version)
    assert np.array_equal(truth.joints["rod"].q, case.exact(case.times).joints["rod"].q)


@pytest.mark.parametrize("jobs", [1, 2])
def test_each_worker_s_blas_pools_get_its_share_of_the_cores(tmp_path, jobs):
    """As many workers as cores, each with BLAS pools as wide as the machine, oversubscribe it: a worker's
    pools take cores // jobs threads (at least one), read back inside the worker from the libraries themselves."""
    specs, _ = expand(cases=["pivoted_rod"], engines=["threads"], integrators=["rk4"], dts=[1e-2, 5e-3],
                      params={"t_final": 0.1})
    store = Store(tmp_path).create({})
    run_matrix(specs, store, jobs=jobs, timing=QUICK)
    share = max(1, (os.cpu_count() or 1) // jobs)
    seen = [r.audit["blas_threads"] for r in store.records()]
    assert len(seen) == 2 and all(blas and set(blas) == {share} for blas in seen), (share, seen)


def test_no_worker_outlives_its_matrix(tmp_path):
    """SIGKILL the parent of a running matrix (no handler of its own can run): its workers are
    gone at once (the kernel's parent-death signal), not left running as orphans."""
    import psutil

    proc = _cli("run", "--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--integrator", "rkmk4",
                "--dt", "1e-4",
                "--jobs", "2", "--out", str(tmp_path / "r"))
    parent = psutil.Process(proc.pid)
    workers = []
    while len(workers) < 2 and proc.poll() is None:  # each run takes ~25 s: the workers are busy
        workers = parent.children()
        time.sleep(0.1)
    assert len(workers) == 2, proc.communicate()[1][-2000:]
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    gone, alive = psutil.wait_procs(workers, timeout=ORPHAN_GRACE_S)
    assert not alive, [w.pid for w in alive]


def test_default_steps_fit_each_cases_sampling():
    """The default steps that do not divide a case's sample interval are left out for that case (the
    Andrews squeezer is sampled every 1 ms, the Test Set's grid: no 1e-2 step); a step given on the
    command line is never changed, and is refused naming the fix."""
    from dalembert.harness.matrix import DEFAULT_DTS

    specs, _ = expand(cases=["andrews_squeezer", "four_bar"], engines=["reference"])
    steps = {(s.case, s.settings.dt) for s in specs if s.settings.dt is not None}
    assert DEFAULT_DTS == (1e-2, 5e-3, 2e-3, 1e-3)
    assert steps == {("andrews_squeezer", 1e-3)} | {("four_bar", dt) for dt in DEFAULT_DTS}
    with pytest.raises(ValueError, match="does not divide the sample interval"):
        expand(cases=["andrews_squeezer"], engines=["reference"], dts=[1e-2])


def test_a_free_worker_keeps_to_its_sweep_and_otherwise_takes_a_sweep_nobody_holds():
    """Runs sharing an engine's compiled program (case, engine, integrator, options: a step sweep) go to the worker
    that ran the last of them; a worker without one takes the next run of a group no busy worker is on."""
    from types import SimpleNamespace

    from dalembert.harness.pool import _take, affinity

    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4", "euler", "rkmk4"],
                      dts=[1e-2, 5e-3, 2e-3])
    sweeps = [s.settings.integrator for s in specs[::3]]  # expand's order: a sweep's three runs in a row
    assert [s.settings.integrator for s in specs] == [i for i in sweeps for _ in range(3)]
    queue = [(affinity(s), s) for s in reversed(specs)]
    a, b = SimpleNamespace(group=None), SimpleNamespace(group=None)
    first = _take(queue, a, set())
    a.group = affinity(first)
    second = _take(queue, b, {a.group})  # plain order would give b the rk4 sweep's second run
    b.group = affinity(second)
    assert (first.settings.integrator, second.settings.integrator) == tuple(sweeps[:2])
    assert [_take(queue, a, {b.group}).settings.integrator for _ in range(2)] == [sweeps[0]] * 2
    assert _take(queue, a, {b.group}).settings.integrator == sweeps[2]  # its sweep done: the one nobody holds
    assert sorted(s.settings.integrator for _, s in queue) == sorted([sweeps[1]] * 2 + [sweeps[2]] * 2)


def test_a_case_is_built_once_for_its_runs(monkeypatch):
    """Expansion, truth, and every run of one case variant share one build of the case and one
    computation of its version (a content hash of the whole case)."""
    from collections import OrderedDict

    from dalembert.case import Case
    from dalembert.harness import truths

    monkeypatch.setattr(truths, "_BUILT", OrderedDict())
    hashed = []
    version = Case.version.fget
    monkeypatch.setattr(Case, "version", property(lambda self: hashed.append(self.name) or version(self)))
    specs, _ = expand(cases=["pendulum"], engines=["reference"], integrators=["rk4", "euler"], dts=[1e-2, 5e-3],
                      params={"t_final": 0.2})
    assert len(specs) == 4 and hashed == ["pendulum"]
    (case, made), = truths.build(specs).values()
    records = [execute(s, QUICK, made)[0] for s in specs]
    assert [r.status for r in records] == ["ok"] * 4 and hashed == ["pendulum"]
    assert truths.built_case("pendulum", {"t_final": 0.2})[0] is case
    # another variant is another case
    assert truths.built_case("pendulum", {"t_final": 0.1})[0].t_final == 0.1 and hashed == ["pendulum"] * 2
