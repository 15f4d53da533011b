"""Reliability: every bad input refused cleanly before anything runs, no silent wrong result,
nothing lost when a run, a worker, the parent or the cluster fails, a store is data, one writer.

Each bad input: the command, its exit status, a phrase its message must hold, and that
nothing was written.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

from dalembert.harness.cli import main
from dalembert.store import Store
from engine_runs import installed
from installed import needs

TINY = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2", "--param", "t_final=0.5",
        "--quick"]

BAD_RUNS = [  # (flags of `dalembert run`, phrase of the message)
    (["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--param", "t_final=2", "--dt", "1e-300"],
     "more than 1e+08"),
    (["--case", "pivoted_rod", "--param", "length=0"], "pivoted_rod.length: must be positive (m), got 0.0"),
    (["--case", "pivoted_rod", "--param", "radius=-0.01"], "pivoted_rod.radius: must be positive"),
    (["--case", "particle_box", "--param", "spacing=1,0,3"], "particle_box.spacing: must be positive"),
    (["--case", "free_top", "--param", "length=5"], "--param length: no selected case has this parameter"),
    (["--case", "pivoted_rod", "--param", "lenght=2"], "did you mean 'length'"),
    (["--param", "t_final=1", "--param", "t_final=2"], "--param t_final: given twice"),
    (["--case", "free_top", "--param", "t_final=1e12"], "1e+14 samples"),
    (["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--rtol", "1e-6"],
     "--rtol: no selected integrator is adaptive"),
    (["--case", "free_top", "--engine", "reference", "--integrator", "dop853", "--dt", "1e-3"],
     "--dt: no selected integrator takes a fixed step"),
    (["--case", "free_top", "--engine", "reference", "--integrator", "dop853", "--rtol", "1e-300"],
     "below what double precision resolves"),
    (["--dt", ","], "--dt: no value given"),
    (["--rtol=-1e-6"], "--rtol: must be positive"),
    (["--timeout", "nan"], "--timeout: must be a positive number"),
    (["--timeout", "-5"], "--timeout: must be a positive number"),
    (["--jobs", "0"], "--jobs: must be at least 1"),
    (["--out", ""], "--out: empty"),
    (["--engine", "mujoco", "--option", "node=ep"], "--option node: no selected engine's integrator takes it"),
    (["--engine", "exudyn", "--option", "node=quaternion"], "--option node=quaternion: unknown 'quaternion' — use one of rotvec-lg, ep, rxyz"),
    (["--case", "free_tops"], "did you mean 'free_top'"),
    (["--resume", "nowhere"], "is not a results directory"),
]


@pytest.mark.parametrize("flags,phrase", BAD_RUNS, ids=[" ".join(f) for f, _ in BAD_RUNS])
def test_a_bad_run_command_is_refused_and_writes_nothing(flags, phrase, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", *flags]) == 2
    err = capsys.readouterr().err
    assert phrase in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_an_unreachable_scheduler_writes_nothing(tmp_path, capsys, monkeypatch):
    # nothing listens on port 9: refused at once, but Dask retries until the connect limit (10 s); what is
    # checked, the refusal and the empty --out, does not depend on that limit
    monkeypatch.setattr("dalembert.harness.commands.run.SCHEDULER_CONNECT_S", 1.0)
    out = tmp_path / "r"
    assert main(["run", *TINY, "--scheduler", "tcp://127.0.0.1:9", "--out", str(out)]) == 2
    assert "--scheduler tcp://127.0.0.1:9: cannot connect" in capsys.readouterr().err
    assert not out.exists()


def test_duplicates_are_merged_and_jobs_capped_with_a_word(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", *TINY, "--dt", "1e-2", "--jobs", "1000", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "--dt: 0.01 given more than once" in err and "--jobs 1000" in err
    assert len(Store(out).records()) == 1 and Store(out).manifest()["jobs"] == os.cpu_count()


def test_flags_given_with_resume_are_refused(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", *TINY, "--out", str(out)]) == 0
    assert main(["run", "--resume", str(out), "--dt", "1e-3", "--case", "free_top"]) == 2
    assert "--case, --dt cannot change a matrix already made" in capsys.readouterr().err
    assert main(["run", "--resume", str(out), "--quick"]) == 2  # the manifest fixes how its runs are timed too
    assert "--quick cannot change a matrix already made" in capsys.readouterr().err


# ---------------------------------------------------------------- no silent wrong result
def test_a_run_that_never_moved_is_a_failure_not_ok():
    """An engine that leaves the state where it started while the truth moves (here: one that
    drops the follower force, so the rod stays put) is stored failed, never ok with 'errors'."""
    from broken_adapters import Still
    from dalembert.adapters import adapter_names, register_adapter
    from dalembert.harness.execute import QUICK, execute
    from dalembert.harness.matrix import expand

    if "still" not in adapter_names():
        register_adapter("still", Still)
    (spec,), _ = expand(cases=["pivoted_rod"], engines=["still"], integrators=["rk4"], dts=[1e-2])
    record, npz = execute(spec, QUICK)
    assert record.status == "failed" and "never left its initial value" in record.message and npz is None


# ---------------------------------------------------------------- damaged and tampered stores
@pytest.fixture(scope="module")
def made_store(tmp_path_factory):
    """A store of two runs, made once for the module: the tests that damage or change one get a copy each."""
    out = tmp_path_factory.mktemp("made") / "store"
    assert main(["run", *TINY, "--integrator", "euler", "--out", str(out)]) == 0
    return out


@pytest.fixture
def store(made_store, tmp_path):
    """A copy of ``made_store``, this test's own (a store holds no path of its own: the copy is a store)."""
    out = tmp_path / "store"
    shutil.copytree(made_store, out)
    return Store(out)


def _damage(path, text="{\"key\": "):
    with open(path, "w") as fh:
        fh.write(text)


@pytest.mark.parametrize("damage,phrase", [
    (lambda s: _damage(os.path.join(s.rows_dir, sorted(s.done_keys())[0] + ".json")), "cannot be read as a stored run"),
    (lambda s: _damage(os.path.join(s.path, "manifest.json")), "manifest.json: cannot be read as its manifest"),
    (lambda s: [os.remove(os.path.join(s.traj_dir, f)) for f in os.listdir(s.traj_dir)], ".npz: missing"),
    (lambda s: [_damage(os.path.join(s.traj_dir, f), "not a zip") for f in os.listdir(s.traj_dir)],
     "cannot be read as a trajectory"),
    (lambda s: _damage(os.path.join(s.rows_dir, sorted(s.done_keys())[0] + ".json"), "{\"key\": 1}"),
     "not a run dalembert wrote"),
])
def test_a_damaged_store_gets_a_message_naming_the_file(store, damage, phrase, tmp_path, capsys):
    damage(store)
    assert main(["report", store.path]) == 2
    err = capsys.readouterr().err
    assert phrase in err and store.path in err and "Traceback" not in err, err


def test_stray_files_in_a_store_are_not_rows(store):
    with open(os.path.join(store.rows_dir, "notes.txt"), "w") as fh:
        fh.write("mine")
    assert main(["report", store.path]) == 0


def test_resume_imports_no_module_a_store_names(store, tmp_path):
    """A manifest whose spec names another module as the adapter: resume takes the adapter from
    the registry (the module named here would exit the process with status 42 if imported)."""
    evil = tmp_path / "evil_adapter.py"
    evil.write_text("import os\nos._exit(42)\n")
    manifest = store.manifest()
    for spec in manifest["specs"]:
        spec["adapter"] = "evil_adapter:Adapter"
    store.write_manifest(manifest)
    os.remove(os.path.join(store.rows_dir, sorted(store.done_keys())[0] + ".json"))
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    proc = subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", "--resume", store.path], env=env,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert [r.status for r in store.records()] == ["ok", "ok"]


def test_resume_refuses_rows_of_another_matrix(store, tmp_path, capsys):
    other = tmp_path / "other"
    assert main(["run", *TINY, "--integrator", "rkmk4", "--out", str(other)]) == 0
    shutil.copy(os.path.join(other, "manifest.json"), os.path.join(store.path, "manifest.json"))
    assert main(["run", "--resume", store.path]) == 2
    assert "not in its manifest" in capsys.readouterr().err


@pytest.mark.long
def test_a_run_writes_nothing_outside_its_store(tmp_path, monkeypatch):
    """Every built-in engine, from a clean working directory: only --out is written (no engine log
    files). The engines are named: other tests register deliberately broken ones in this process."""
    from dalembert.adapters.registry import BUILTIN

    monkeypatch.chdir(tmp_path)
    # every integrator of every engine (an engine's solvers may each have their own files to write), but
    # MJX, which writes nothing of its own and compiles for ~6 s per integrator and precision: one of each
    # (those installed: an optional engine outside dalembert[all], MuJoCo Warp, is absent from a fresh make test)
    # One worker: each worker loads every engine before its first run (Warp's, Newton's: seconds), and what an
    # engine writes does not depend on how many workers share the runs (two: 14 s of CPU, one: 9 s).
    engines = [a for name in sorted(BUILTIN) if name != "mjx" and installed(name) for a in ("--engine", name)]
    assert main(["run", "--case", "pivoted_rod", *engines, "--dt", "1e-2", "--rtol", "1e-6", "--param",
                 "t_final=0.2", "--quick", "--jobs", "1", "--out", "r"]) == 0
    # in this process too: where other tests left JAX's runtime up, the workers start from a forkserver
    # (``harness.pool``), not forked from it
    assert main(["run", "--case", "pivoted_rod", "--engine", "mjx", "--integrator", "euler", "--dt", "1e-2", "--param",
                 "t_final=0.2", "--quick", "--out", "m"]) == 0
    assert sorted(os.listdir(tmp_path)) == ["m", "r"]


def test_rows_are_strict_json(tmp_path):
    """A diverged run's row holds no bare NaN (strict JSON readers reject it): null, status says why."""
    out = tmp_path / "r"
    assert main(["run", "--case", "free_top_fast_spin", "--engine", "reference", "--integrator", "euler", "--dt",
                 "1e-2", "--param", "spin=500", "--param", "t_final=2", "--out", str(out)]) == 0
    (row,) = Store(out).rows()
    assert row["status"] == "diverged"
    text = open(os.path.join(out, "rows", row["key"] + ".json")).read()
    json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


# ---------------------------------------------------------------- one writer, faults of the parent
def _cli(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "dalembert.harness.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


SLOW = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--integrator", "rkmk4", "--dt", "1e-4",
        "--jobs", "2"]


def _busy_workers(proc, n=2):
    """The ``n`` workers of the ``dalembert run`` ``proc`` once they are all started: its forked children (the
    parent's command line), not a short-lived program it runs (a library looking for a shared library)."""
    import psutil

    parent, workers = psutil.Process(proc.pid), []
    while len(workers) < n and proc.poll() is None:
        try:
            workers = [c for c in parent.children() if c.cmdline() == parent.cmdline()]
        except psutil.NoSuchProcess:  # a child that ended while being read
            workers = []
        time.sleep(0.1)
    return workers


def test_a_second_writer_is_refused_naming_the_first(tmp_path, capsys):
    """The first writer another process (its lock is the kernel's, per open file); the second and third asked in
    this one, as ``main`` (their refusal is the command line's exit status and message, not a process's)."""
    out = tmp_path / "r"
    first = _cli("run", *SLOW, "--out", str(out))
    try:
        assert len(_busy_workers(first)) == 2
        assert main(["run", "--resume", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"PID {first.pid} on" in err and "one store takes one writer" in err, err
        assert main(["run", *TINY, "--out", str(out)]) == 2  # a fresh run into the same --out
        err = capsys.readouterr().err
        assert "already being written" in err, err
    finally:
        first.kill()
        first.wait()


@pytest.mark.parametrize("sig,group", [(signal.SIGTERM, False), (signal.SIGINT, True), (signal.SIGTERM, True)],
                         ids=["SIGTERM", "Ctrl-C", "group SIGTERM"])
def test_stopping_the_parent_ends_cleanly_and_says_how_to_resume(sig, group, tmp_path):
    """SIGTERM, Ctrl-C (SIGINT to the whole process group, as a terminal sends it), or SIGTERM to the
    whole group (`kill -TERM -<pgid>`, a service manager's stop): exit 130, every finished run stored,
    no worker left, no traceback (a worker's included), the --resume command printed."""
    import psutil

    out = tmp_path / "r"
    # SIGINT as in a terminal's foreground job: Python's default handler, whatever this test process
    # inherited (a process that ignores SIGINT passes SIG_IGN on, and Python then keeps it ignored)
    proc = _cli("run", *SLOW, "--out", str(out), start_new_session=True,
                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    workers = _busy_workers(proc)
    assert len(workers) == 2
    if group:
        os.killpg(proc.pid, sig)
    else:
        proc.send_signal(sig)
    _, err = proc.communicate()
    assert proc.returncode == 130 and f"dalembert run --resume {out}" in err, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    gone, alive = psutil.wait_procs(workers, timeout=60)
    assert not alive
    Store(out).writer().release()  # the lock was released: --resume can take it


# ---------------------------------------------------------------- faults of a worker, a full disk
# Two runs of the reference on one worker (~1.3 s of CPU each on this machine's cores, the first ~0.04 s of a
# worker's CPU being its start): a worker is mid-run once it has used MID_RUN_CPU_S.
STOPPABLE = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-3,2e-3", "--param",
             "t_final=10", "--quick", "--jobs", "1"]
MID_RUN_CPU_S = 0.2


def _strip(rows):
    """Rows less where and how long each run ran (``TIMING_FIELDS``)."""
    return [{k: v for k, v in r.items() if k not in TIMING_FIELDS} for r in rows]


@pytest.fixture(scope="module")
def stoppable_clean(tmp_path_factory):
    """``STOPPABLE`` run uninterrupted, once for the module: what each stopped and resumed matrix must equal."""
    clean = tmp_path_factory.mktemp("clean") / "r"
    assert main(["run", *STOPPABLE, "--out", str(clean)]) == 0
    return Store(clean)


@pytest.mark.long
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_worker_stopped_from_outside_ends_its_run_without_failing_it(sig, tmp_path, stoppable_clean):
    """SIGTERM (an operator, a shutdown) or SIGKILL (the out-of-memory killer) to one worker mid-run: that
    run is not stored (it did not fail, it was not run), the parent names it and exits 4 with the --resume
    command, the rest of the matrix is stored; --resume runs it, and the store then holds the rows of an
    uninterrupted matrix."""
    import psutil

    from dalembert.harness.matrix import RunSpec

    out = tmp_path / "r"
    proc = _cli("run", *STOPPABLE, "--out", str(out))
    (worker,) = _busy_workers(proc, 1)
    while proc.poll() is None:
        try:
            if sum(worker.cpu_times()[:2]) >= MID_RUN_CPU_S:
                break
        except psutil.NoSuchProcess:  # a worker the pool ended (its runs done) while it was read: follow the next
            (worker,) = _busy_workers(proc, 1) or (worker,)
            continue
        time.sleep(0.02)
    worker.send_signal(sig)
    _, err = proc.communicate()
    store = Store(out)
    (missing,) = [RunSpec.from_json(s) for s in store.manifest()["specs"] if RunSpec.from_json(s).key
                  not in store.done_keys()]
    said = f"{missing.case} {missing.engine} {missing.settings.label()}: its worker was stopped by {sig.name}"
    assert proc.returncode == 4 and said in err and f"dalembert run --resume {out}" in err, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert [r.status for r in store.records()] == ["ok"]  # the other run; nothing stored as failed
    resumed = _cli("run", "--resume", str(out))
    _, err = resumed.communicate()
    assert resumed.returncode == 0, err
    assert _strip(store.rows()) == _strip(stoppable_clean.rows())


def _late_worker(sent):
    sent.wait()  # the parent's SIGTERM is sent before this worker sets its signals
    from dalembert.harness.lifetime import die_with_parent

    die_with_parent()  # ends here when the SIGTERM was held for it
    os._exit(0)


def test_a_sigterm_before_a_worker_is_ready_ends_it_quietly():
    """A worker forked (``sigterm_held``) from a process whose SIGTERM handler raises KeyboardInterrupt (the
    command line's) and sent SIGTERM before it has set its own signals: the signal waits for
    ``die_with_parent``, and the worker dies of it (exit code -SIGTERM); unheld, it meets the parent's handler (a
    KeyboardInterrupt traceback, exit code 1) or is lost in the fork (the worker goes on: exit code 0)."""
    import multiprocessing as mp

    from dalembert.harness.lifetime import sigterm_held

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    ctx = mp.get_context("fork")
    sent = ctx.Event()
    before = signal.signal(signal.SIGTERM, interrupt)
    try:
        with sigterm_held():
            proc = ctx.Process(target=_late_worker, args=(sent,))
            proc.start()
    finally:
        signal.signal(signal.SIGTERM, before)
    proc.terminate()  # SIGTERM
    sent.set()
    proc.join()
    assert proc.exitcode == -signal.SIGTERM


# In a fresh interpreter (this one may have JAX running, from other tests): which start method a matrix's workers get
# with JAX imported, then with its runtime up.
JAX_CONTEXT = """
import jax
from dalembert.harness.pool import _context
imported = _context().get_start_method()
jax.numpy.zeros(1).block_until_ready()
print(imported, _context().get_start_method())
"""


@needs("jax")
def test_workers_are_not_forked_from_a_process_running_jax():
    """JAX's runtime threads are native (``threading`` counts one thread), and a fork copies their locks: once
    JAX has computed (an MJX run in a notebook before ``api.run``), workers start from a forkserver; JAX
    imported but idle still forks (``dalembert run`` imports MJX's adapter in the parent)."""
    done = subprocess.run([sys.executable, "-c", JAX_CONTEXT], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["fork", "forkserver"], done.stderr


# `dalembert run` with its store's disk full from the second run's row on (the parent writes the store: a
# write there raises ENOSPC as a full disk's would)
FULL_DISK = """
import errno, os, sys
import dalembert.store
from dalembert.harness.cli import main

write, rows = dalembert.store.atomic_write, []
def full(path, data):
    if os.sep + "rows" + os.sep in path:
        rows.append(path)
        if len(rows) > 1:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return write(path, data)
dalembert.store.atomic_write = full
sys.exit(main(sys.argv[1:]))
"""


def test_a_full_disk_is_one_error_naming_the_store(tmp_path):
    """The store's disk fills mid-matrix: one error naming the store and the fix (exit 2), no traceback
    from the parent or any worker, the run stored before kept; --resume, the disk freed, finishes it."""
    out = tmp_path / "r"
    matrix = [*TINY, "--integrator", "euler", "--integrator", "rkmk4", "--jobs", "2", "--out", str(out)]
    proc = subprocess.run([sys.executable, "-c", FULL_DISK, "run", *matrix], capture_output=True, text=True)
    err = proc.stderr
    assert proc.returncode == 2 and f"dalembert: error: {out}: cannot store run free_top reference" in err, err
    assert "No space left on device" in err and f"dalembert run --resume {out}" in err, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err and err.count("dalembert: error") == 1, err
    assert len(Store(out).done_keys()) == 1
    assert main(["run", "--resume", str(out)]) == 0
    assert [r.status for r in Store(out).records()] == ["ok"] * 3


def test_a_dask_task_whose_process_is_stopped_is_lost_not_failed(tmp_path):
    """A Dask task's run process stopped by SIGTERM: the task raises ``WorkerStopped`` naming the run (the
    run is lost to the infrastructure, not stored as failed), as a local worker's."""
    import threading

    import psutil

    from dalembert.harness.dask import WorkerStopped, execute_isolated
    from dalembert.harness.execute import QUICK
    from dalembert.harness.matrix import expand

    (spec,), _ = expand(cases=["free_top"], engines=["reference"], integrators=["rk4"], dts=[1e-4])
    result = {}

    def task():
        try:
            result["value"] = execute_isolated(spec.to_json(), vars(QUICK), None, 600.0)
        except BaseException as e:  # noqa: BLE001 - what the task raised is the subject
            result["value"] = e

    thread = threading.Thread(target=task)
    thread.start()
    me = psutil.Process()
    children = []
    while not children and thread.is_alive():
        children = [c for c in me.children() if "dalembert.harness.worker" in c.cmdline()]
        time.sleep(0.05)
    (child,) = children
    child.send_signal(signal.SIGTERM)
    thread.join()
    stopped = result["value"]
    assert isinstance(stopped, WorkerStopped), stopped
    assert str(stopped).startswith("free_top reference rk4 dt=0.0001: its worker was stopped by SIGTERM"), stopped


# ---------------------------------------------------------------- the cluster fails
class _Cluster:
    """A Dask scheduler and one worker, each its own process on loopback (so the scheduler can be killed)."""

    def __init__(self, path):
        self.file = str(path / "scheduler.json")
        self.scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host",
                                           "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", self.file],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while not os.path.exists(self.file):
            time.sleep(0.1)
        time.sleep(0.5)  # the file is written before the scheduler listens
        self.worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file",
                                        self.file, "--nworkers", "1", "--nthreads", "1", "--no-dashboard"],
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    @property
    def address(self):
        with open(self.file) as fh:
            return json.load(fh)["address"]

    def stop(self):
        for proc in (self.worker, self.scheduler):
            proc.kill()
            proc.wait()


# everything but where and how long a run ran
TIMING_FIELDS = {"wall_s_median", "wall_s_min", "wall_s_max", "wall_s_repeats", "overhead_s", "readback_s", "build_s", "worker_s",
                 "stepping_total_s", "provenance", "load_start", "load_end", "concurrent", "repeats"}


@pytest.mark.long
def test_a_lost_scheduler_loses_no_work(tmp_path):
    """The scheduler killed mid-matrix: the runs it lost are not stored (exit 4, the --resume
    command printed), and --resume on a new cluster finishes the matrix identical to an
    uninterrupted local one."""
    # four short runs: each Dask task starts a Python process (~1 s), so the kill lands while some wait
    selection = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--integrator", "euler",
                 "--dt", "1e-2,5e-3", "--param", "t_final=1", "--quick"]
    out = tmp_path / "dask"
    (tmp_path / "a").mkdir()
    first = _Cluster(tmp_path / "a")
    try:
        # the client gives up on a vanished scheduler after its connect timeout (Dask's default 30 s):
        # what is tested is that nothing is lost, not how long the client waits
        env = {**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"}
        proc = _cli("run", *selection, "--scheduler", first.address, "--out", str(out), env=env)
        while len(Store(out).done_keys()) < 1 and proc.poll() is None:
            time.sleep(0.1)
        first.scheduler.kill()
        _, err = proc.communicate()
    finally:
        first.stop()
    stored = len(Store(out).done_keys())
    assert proc.returncode == 4 and "lost to the infrastructure" in err and f"--resume {out}" in err, err
    assert "Traceback" not in err and 1 <= stored < 4
    assert all(r.status == "ok" for r in Store(out).records())  # nothing lost was stored as failed
    (tmp_path / "b").mkdir()
    second = _Cluster(tmp_path / "b")
    try:
        resumed = _cli("run", "--resume", str(out), "--scheduler", second.address)
        _, err = resumed.communicate()
    finally:
        second.stop()
    assert resumed.returncode == 0, err
    local = tmp_path / "local"
    assert main(["run", *selection, "--out", str(local)]) == 0
    assert _strip(Store(out).rows()) == _strip(Store(local).rows())


@pytest.mark.parametrize("flags,phrase", [(["--cost-threshold", "-1"], "--cost-threshold: a growth factor"),
                                          (["--threshold", "nan"], "--threshold: a growth factor")])
def test_compare_refuses_a_meaningless_threshold(store, flags, phrase, capsys):
    assert main(["compare", store.path, store.path, *flags]) == 2
    assert phrase in capsys.readouterr().err


def test_debug_shows_the_traceback_the_message_hides(capsys):
    """In process (the command line's ``main``; no interpreter started for an argument's error): without
    ``--debug`` the one-line message, with it the error raised out of ``main``, whose traceback the interpreter
    then prints."""
    from dalembert.registry import UnknownNameError

    assert main(["run", "--case", "free_tops"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "did you mean" in err
    with pytest.raises(UnknownNameError, match="free_tops"):
        main(["--debug", "run", "--case", "free_tops"])


def test_a_closed_pipe_is_not_an_error(monkeypatch, capsys):
    """`dalembert cases | head -1`: the reader leaves early and the next write breaks the pipe;
    that ends the command quietly, not with a BrokenPipeError traceback."""
    class Closed:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            pass

    monkeypatch.setattr(sys, "stdout", Closed())
    assert main(["cases", "--verbose"]) == 0
