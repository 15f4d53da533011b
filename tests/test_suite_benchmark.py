"""benchmarks/suite.py's pure parts: pytest's durations and summary lines, JAX's compile log, the CPU meter's choice.

The samples are pytest's and JAX's own output (pytest 8 ``-q --durations=0`` of this suite under xdist; JAX 0.10's
dispatch and compiler loggers at DEBUG, one jitted function compiled cold, then again from the persistent cache).
No test here runs the suite.
"""

import os
import subprocess
import sys
import textwrap

import pytest
from benchmark_modules import benchmark


# pytest's --durations lines: several phases of one file, a file with setup only, lines that are not durations
DURATIONS = """\
-- Docs: https://docs.pytest.org/en/stable/how-to/capture-warnings.html
============================== slowest durations ===============================
56.18s call     tests/test_check_engine.py::test_the_built_in_engines_pass[pinocchio]
5.91s setup    tests/test_case_contract.py::test_truth_is_finite_and_starts_at_the_initial_state[flyball_governor]
4.92s call     tests/test_case_contract.py::test_an_independent_solution_agrees_with_the_truth[bricard]
4.68s setup    tests/test_case_contract.py::test_truth_is_finite_and_starts_at_the_initial_state[andrews_squeezer]
4.11s setup    tests/test_contact_report.py::test_contact_figures_appear_for_contact_cases_only
1.73s call     tests/test_contact_report.py::test_the_contact_forces_table_shows_each_runs_figures_and_not_measured_where_none
0.07s call     tests/test_robot_scaling.py::test_the_scaling_section_draws_robots_against_dof_and_not_one_robot_alone
0.00s teardown tests/test_robot_scaling.py::test_robot_runs_are_placed_by_their_degrees_of_freedom_per_engine_line
(6423 durations < 0.005s hidden.  Use -vv to show these durations.)
=========================== short test summary info ============================
FAILED tests/test_n_four_bar.py::test_a_scipy_failure_in_a_projected_adaptive_run_ends_as_data_with_scipys_message
1 failed, 2443 passed, 82 skipped, 1 xfailed, 23 warnings in 263.18s (0:04:23)
"""

# one process's log: three jitted functions compiled (cache misses), then a second process's: the same three from
# the persistent cache (JAX times the fetch under the same "Finished XLA compilation" line)
JAX_COLD = """\
Finished tracing convert_element_type for jit in 0.000351667 sec
Finished jaxpr to MLIR module conversion jit(convert_element_type) in 0.092681646 sec
get_compile_options: num_replicas=1 num_partitions=1 device_assignment=[[CpuDevice(id=0)]]
PERSISTENT COMPILATION CACHE MISS for 'jit_convert_element_type' with key 'jit_convert_element_type-364ca4604dcb2da2a01914b5d3ee3dffff2d0de878f9fad019ea08027ac8a1c2'
'jit_convert_element_type' took at least 0.00 seconds to compile (0.02s)
Finished XLA compilation of jit(convert_element_type) in 0.023472309 sec
Finished tracing broadcast_in_dim for jit in 0.000354528 sec
Finished XLA compilation of jit(broadcast_in_dim) in 0.055793285 sec
Finished tracing <lambda> for jit in 0.001299381 sec
Finished jaxpr to MLIR module conversion jit(<lambda>) in 0.004081249 sec
Finished XLA compilation of jit(<lambda>) in 0.032487631 sec
"""
JAX_WARM = """\
Finished tracing convert_element_type for jit in 0.000309706 sec
Persistent compilation cache hit for 'jit_convert_element_type' with key 'jit_convert_element_type-364ca4604dcb2da2a01914b5d3ee3dffff2d0de878f9fad019ea08027ac8a1c2'
Finished XLA compilation of jit(convert_element_type) in 0.004596710 sec
Persistent compilation cache hit for 'jit_broadcast_in_dim' with key 'jit_broadcast_in_dim-ed834b312d98d00f8dd04602b1d62024cf5219ced2a4ea3e91be7899a10f67ef'
Finished XLA compilation of jit(broadcast_in_dim) in 0.001652479 sec
Persistent compilation cache hit for 'jit__lambda' with key 'jit__lambda-ef11354199991478df099b993bcb41bfbc5b74a76bb06c789cd163cb297a2837'
Finished XLA compilation of jit(<lambda>) in 0.001736641 sec
"""

# the CPU an orphan burns in the meter's test: enough to stand far above a start's noise (~0.02 CPU-s)
BURN_S = 0.5
# what the cgroup may count beyond the orphan's burn: the parent's and the orphan's interpreter starts
STARTS_S = 1.0


@pytest.fixture()
def suite():
    with benchmark("suite") as module:
        yield module


def test_each_file_sums_its_tests_setup_call_and_teardown(suite):
    files = suite.file_seconds(DURATIONS)
    assert files == pytest.approx({
        "tests/test_check_engine.py": 56.18, "tests/test_case_contract.py": 5.91 + 4.92 + 4.68,
        "tests/test_contact_report.py": 4.11 + 1.73, "tests/test_robot_scaling.py": 0.07})
    top = suite.top_files(files, k=2)
    total = 56.18 + 15.51 + 5.84 + 0.07
    assert [name for name, _, _ in top] == ["tests/test_check_engine.py", "tests/test_case_contract.py"]
    assert top[1][1] == pytest.approx(15.51) and top[1][2] == pytest.approx(15.51 / total)


def test_colour_codes_do_not_hide_a_duration_or_the_summary(suite):
    line = "\x1b[32m12.50s call     tests/test_x.py::test_y[a::b c]\x1b[0m\n\x1b[32m3 passed\x1b[0m in 1.00s\n"
    assert suite.file_seconds(line) == {"tests/test_x.py": 12.5}
    assert suite.outcomes(line) == {"passed": 3}


def test_the_outcomes_are_the_last_summary_line_s(suite):
    assert suite.outcomes(DURATIONS) == {"failed": 1, "passed": 2443, "skipped": 82, "xfailed": 1, "warnings": 23}
    assert suite.outcomes("2449 passed, 14 skipped, 1 xfailed, 41 warnings in 420.21s (0:07:00)\n") == {
        "passed": 2449, "skipped": 14, "xfailed": 1, "warnings": 41}
    assert suite.outcomes("= 1 error, 1 warning in 0.5s =") == {"errors": 1, "warnings": 1}
    assert suite.outcomes("collected 5 items\n") == {}
    # a failed test's captured output can hold an inner pytest's summary (a test that runs pytest): not the suite's
    inner = "----------------------------- Captured stdout call -----------------------------\n3 passed in 0.02s\n"
    assert suite.outcomes(inner + "1 failed, 2 passed in 9.10s\n") == {"failed": 1, "passed": 2}


def test_jax_compiles_count_every_finished_compilation_and_its_cache_hits(suite):
    cold = suite.jax_compiles([JAX_COLD])
    assert (cold.compiles, cold.cache_hits) == (3, 0)
    assert cold.compile_wall_s == pytest.approx(0.023472309 + 0.055793285 + 0.032487631)
    both = suite.jax_compiles([JAX_COLD, JAX_WARM])
    assert (both.compiles, both.cache_hits) == (6, 3)
    assert both.compile_wall_s == pytest.approx(0.119739055)


def test_without_a_cgroup_the_meter_falls_back_to_rusage_and_says_it_undercounts(suite, tmp_path):
    groups = tmp_path / "cgroup"
    (groups / "cpuacct").mkdir(parents=True)
    (groups / "cpuacct" / "cpuacct.usage").write_text("0\n")  # a v1 mount's marker, on a plain file system
    proc = tmp_path / "self-cgroup"
    proc.write_text("2:cpuacct:/\n0::/\n")
    meter = suite.choose_meter(root=str(groups), proc_cgroup=str(proc), name="probe")
    assert meter.source == "rusage" and "UNDERCOUNTS" in meter.note
    assert f"{groups / 'cpuacct'}: not a cgroup file system" in meter.note
    assert f"{groups}: no cgroup v2 there" in meter.note
    assert not (groups / "cpuacct" / "probe").exists()  # the directory it tried is gone
    elsewhere = suite.choose_meter(root=str(groups), proc_cgroup=str(tmp_path / "none"), name="probe")
    assert f"{groups / 'cpuacct'}: {tmp_path / 'none'} names no v1 group of this process" in elsewhere.note


def _orphan_cpu(suite, meter):
    """A child that starts a grandchild burning BURN_S CPU-s and exits without waiting for it: what the meter counts
    and what RUSAGE_CHILDREN does."""
    burn = f"import time\nt = time.process_time()\nwhile time.process_time() - t < {BURN_S}:\n    pass\n"
    parent = (f"import subprocess, sys\nsubprocess.Popen([sys.executable, '-c', {burn!r}], start_new_session=True,"
              " stdin=subprocess.DEVNULL)\n")
    before_group, before_rusage = suite.read_cpu_s(meter), suite._rusage_s()
    subprocess.run([sys.executable, "-c", parent], check=True, preexec_fn=suite._joiner(meter))
    suite.settle(meter, linger_s=120.0)  # until the orphan has exited (its wall time depends on the load)
    return suite.read_cpu_s(meter) - before_group, suite._rusage_s() - before_rusage


@pytest.mark.parametrize("version", ["v1", "v2"])
def test_a_cgroup_counts_an_orphan_that_rusage_misses(suite, version):
    root = suite.CGROUP_ROOT if version == "v1" else next(
        (r for r in (suite.CGROUP_ROOT, os.path.join(suite.CGROUP_ROOT, "unified"))
         if os.path.exists(os.path.join(r, "cgroup.controllers"))), "")
    meter = suite.choose_meter(root=root) if root else None
    if meter is None or meter.source != "cgroup" or f"cgroup {version}" not in meter.note:
        if meter is not None:
            suite.release(meter)
        pytest.skip(f"no cgroup {version} group can be made here (not root, or not mounted)")
    try:
        group, rusage = _orphan_cpu(suite, meter)
    finally:
        suite.release(meter)
    assert not os.path.exists(meter.path)
    assert BURN_S <= group < BURN_S + STARTS_S
    assert rusage < BURN_S  # the parent only: the orphan was never waited for


def test_the_hook_logs_a_process_s_compiles_to_its_file_only_and_runs_the_sitecustomize_it_hides(suite, tmp_path):
    pytest.importorskip("jax")
    hook, logs, other = tmp_path / "hook", tmp_path / "logs", tmp_path / "other"
    for d in (hook, logs, other):
        d.mkdir()
    (hook / "sitecustomize.py").write_text(suite.HOOK)
    (other / "sitecustomize.py").write_text("import os\nos.environ['HIDDEN_SITECUSTOMIZE_RAN'] = '1'\n")
    code = textwrap.dedent("""\
        import os, jax, jax.numpy as jnp
        jax.jit(lambda x: jnp.sin(x) * 2)(jnp.ones(3)).block_until_ready()
        print(os.environ.get("HIDDEN_SITECUSTOMIZE_RAN"))
    """)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(hook), str(other)]), **{suite.JAXLOG_ENV: str(logs)})
    env.pop("JAX_LOG_COMPILES", None)
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "1"
    assert "XLA compilation" not in done.stderr
    texts = [p.read_text() for p in logs.iterdir()]
    assert len(texts) == 1  # one process, one file
    found = suite.jax_compiles(texts)
    assert found.compiles >= 1 and found.compile_wall_s > 0  # (the jitted function, and any JAX compiles itself)
    assert "Finished XLA compilation of jit(<lambda>)" in texts[0]


def test_cache_and_jax_cache_together_are_refused_naming_both(suite, tmp_path, capsys):
    with pytest.raises(SystemExit):
        suite.main(["--cache", str(tmp_path), "--jax-cache", "warm"])
    assert "give --cache or --jax-cache, not both" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        suite.main(["--cache", str(tmp_path / "absent")])
    assert f"--cache: {tmp_path / 'absent'} is not a directory" in capsys.readouterr().err
