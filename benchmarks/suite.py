"""Where the test suite's time goes: its whole process tree's CPU, MJX's XLA compiles and each test file's share.

    python -m benchmarks.suite [--json FILE] [--jax-cache cold|warm | --cache DIR] [--log FILE] [-- PYTEST ARGS]

Runs the README's test command's pytest (``python -P -m pytest -n 2 -q -p no:cacheprovider``, in this checkout,
with this interpreter) plus ``--durations=0 --durations-min=0`` and any ``PYTEST ARGS`` (``-- -n 1`` overrides the
workers: the last ``-n`` wins), with ``DALEMBERT_CACHE`` a fresh temporary directory:

- ``--jax-cache cold`` (the default): the directory is empty but for copies of the Pinocchio stepper libraries
  ``make setup`` built (``pinocchio_stepper-*.so`` from the user's cache, ``dalembert.cache.cache_dir()``), so the
  suite does not compile that again (~2 CPU-min) but compiles everything else, MJX's XLA programs first among them;
- ``--jax-cache warm``: the same directory after the suite has run once into it, untimed, so JAX's persistent
  compilation cache (and every other cache under it: Warp's kernels, the environments' metadata) is full;
- ``--cache DIR``: ``DIR`` as it is, neither emptied nor seeded (a cache kept from an earlier run).

It measures the suite's CPU (user + system s) in a cgroup of its own: a cgroup v1 ``cpuacct`` group or a cgroup v2
child of this process's group, where this process may create one (as root). The group counts every process the
suite starts — xdist's workers, the pools' forkserver children, orphans reparented to init that no one waits for —
and nothing else on the machine. Where no group can be made it falls back to ``getrusage(RUSAGE_CHILDREN)``, which
counts only the processes their parents waited for, so it UNDERCOUNTS, and it says so. Every Python process of the
suite logs JAX's ``Finished XLA compilation of ... in X sec`` lines (and its persistent-cache hits) to a file of
its own, through a ``sitecustomize`` put first on ``PYTHONPATH`` (a process started with ``-I`` or with its own
``PYTHONPATH`` does not); the compiles' count and wall seconds are their sum. Each test file's time is its tests'
setup + call + teardown from ``--durations``, summed over the workers (test time, not CPU).

The project's goal is the suite under 4 minutes from a fresh clone on 2 cores while another process keeps them
busy: then the suite gets about one core, so its wall time there is about the CPU this measures, not the wall time
it prints. Measured at bf279fa in a fresh clone after ``make setup`` (``dalembert[all]``: 2455 passed, 82 skipped,
1 xfailed), 2 cores, load ~1 at the start: cold 433 CPU-s in 224 s wall, 161 XLA compiles, 120 s of compile wall
time; warm 303 CPU-s in 158 s (39 of the compiles from the cache, 7 s). So MJX's XLA compiles are ~130 CPU-s of a
cold suite, and even a warm one is ~60 CPU-s over the goal's ~240. The costliest files cold: test_mjx_contact
(11.5 %), test_run_matrix (9.7 %), test_reliability (8.1 %), test_mjx (6.0 %). Load inflates the CPU itself (a
checkout with Newton installed: 587 CPU-s near idle, 644 beside other work). The hook costs no CPU
that shows: ``import dalembert`` 0.21 CPU-s a start with it and without (30 starts each).

Prints the tests passed/failed/skipped, wall s, CPU s, CPU/wall, the JAX compiles and the top ``TOP`` files with
their share; ``--json FILE`` writes ``{"schema": 1, "commit", "dirty", "cpu_s", "wall_s", "cpu_source":
"cgroup"|"rusage", "cpu_note", "jax": {"compiles", "compile_wall_s", "cache_hits"}, "files": {file: s}, "tests":
{"passed": n, ...}, "cache", "pytest_rc", "load", "cores"}``. Exits with pytest's status.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass

# The README's test command (Makefile's ``make test``), without the cache plugin: the checkout stays as it was.
PYTEST = ("-P", "-m", "pytest", "-n", "2", "-q", "-p", "no:cacheprovider")
# Every test's setup, call and teardown, the shortest too (pytest hides those under 5 ms by default).
DURATIONS = ("--durations=0", "--durations-min=0")
CGROUP_ROOT = "/sys/fs/cgroup"
# How long the suite's processes that outlive pytest (a pool's forkserver, Dask's nanny) get to exit before they are
# ended: they exit within a second or two of their parent's pipes closing; their CPU until then is the suite's.
LINGER_S = 10.0
TOP = 15
STEPPER_GLOB = "pinocchio_stepper-*.so"
JAXLOG_ENV = "DALEMBERT_SUITE_JAXLOG"  # the directory the hook logs each process's JAX lines into

# Each process's JAX log: JAX logs its compiles at DEBUG (at WARNING with JAX_LOG_COMPILES=1, which would also print
# them on every subprocess's stderr, where tests read it); the two loggers go to this process's file at DEBUG, and
# what they would have shown anyway (their records at or above the "jax" logger's level) still goes up to it.
HOOK = '''"""Written by benchmarks/suite.py: each process's JAX compile log, in $DALEMBERT_SUITE_JAXLOG/<pid>.log."""
import os
import sys

_dir = os.environ.get("DALEMBERT_SUITE_JAXLOG")
if _dir:
    import logging

    class _Up(logging.Handler):
        def emit(self, record):
            parent = logging.getLogger("jax")
            if record.levelno >= parent.getEffectiveLevel():
                parent.handle(record)

    _file = logging.FileHandler(os.path.join(_dir, f"{os.getpid()}.log"), delay=True)
    _file.setFormatter(logging.Formatter("%(message)s"))
    for _name in ("jax._src.dispatch", "jax._src.compiler"):
        _logger = logging.getLogger(_name)
        _logger.setLevel(logging.DEBUG)
        _logger.propagate = False
        _logger.addHandler(_file)
        _logger.addHandler(_Up())

# the sitecustomize this one hides, if the interpreter has one
import importlib.machinery
import importlib.util

_here = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.machinery.PathFinder.find_spec(
    "sitecustomize", [p for p in sys.path if os.path.abspath(p or os.curdir) != _here])
if _spec is not None and _spec.loader is not None:
    _spec.loader.exec_module(importlib.util.module_from_spec(_spec))
'''

_DURATION = re.compile(r"^(\d+(?:\.\d+)?)s (setup|call|teardown)\s+(\S.*)$")
_OUTCOME = re.compile(r"(\d+) (passed|failed|skipped|xfailed|xpassed|errors?|warnings?|deselected)\b")
_SUMMARY = re.compile(r"\bin \d+(?:\.\d+)?s\b")
_COMPILE = re.compile(r"Finished XLA compilation of .* in (\d+(?:\.\d+)?(?:[eE][-+]?\d+)?) sec")
_CACHE_HIT = re.compile(r"^Persistent compilation cache hit for ")
_PLURAL = {"error": "errors", "warning": "warnings"}  # pytest says "1 error", "2 errors"
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def file_seconds(text):
    """Each test file's time from pytest's ``--durations`` lines: ``{path: s}``, setup + call + teardown summed.

    Parameters
    ----------
    text : str
        pytest's output; lines ``"1.23s call     tests/test_x.py::test_y[a]"`` count, every other line is ignored.
    """
    files = {}
    for line in _ANSI.sub("", text).splitlines():
        m = _DURATION.match(line.strip())
        if m:
            name = m.group(3).split("::", 1)[0]
            files[name] = files.get(name, 0.0) + float(m.group(1))
    return files


def outcomes(text):
    """The counts of pytest's last summary line (``"2444 passed, 12 skipped, 3 warnings in 248.12s"``):
    ``{"passed": n, "failed": n, "skipped": n, ...}``, ``errors``/``warnings`` plural; {} where there is none."""
    for line in reversed(_ANSI.sub("", text).splitlines()):
        counts = _OUTCOME.findall(line)
        if counts and _SUMMARY.search(line):
            return {_PLURAL.get(what, what): int(n) for n, what in counts}
    return {}


@dataclass(frozen=True)
class JaxCompiles:
    """JAX's XLA compiles of a run: ``compiles`` (each ``Finished XLA compilation`` line, a persistent-cache hit
    included: JAX times the fetch under the same line), ``compile_wall_s`` (their seconds summed, s) and
    ``cache_hits`` (those served from the persistent cache)."""

    compiles: int
    compile_wall_s: float
    cache_hits: int


def jax_compiles(texts):
    """``JaxCompiles`` from the hook's log files' texts (an iterable of str, one per process)."""
    n, wall, hits = 0, 0.0, 0
    for text in texts:
        for line in text.splitlines():
            m = _COMPILE.search(line)
            if m:
                n, wall = n + 1, wall + float(m.group(1))
            elif _CACHE_HIT.match(line):
                hits += 1
    return JaxCompiles(n, wall, hits)


def top_files(files, k=TOP):
    """The ``k`` files with the most time: ``[(path, s, share of all files' time)]``, the most first."""
    total = sum(files.values())
    ranked = sorted(files.items(), key=lambda kv: (-kv[1], kv[0]))[:k]
    return [(name, s, s / total if total else 0.0) for name, s in ranked]


# -- the CPU meter ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Meter:
    """How the suite's CPU is counted: ``source`` ``"cgroup"`` (``path`` the group's directory, ``usage`` its file of
    CPU used: ``cpuacct.usage`` in ns for v1, ``cpu.stat``'s ``usage_usec`` for v2) or ``"rusage"``; ``note`` says
    which, or why the fallback."""

    source: str
    path: str | None = None
    usage: str | None = None
    note: str = ""


def _own_groups(proc_cgroup):
    """This process's groups from ``/proc/self/cgroup``: ``{controller: path}``, v2's unified group under ``""``."""
    groups = {}
    try:
        with open(proc_cgroup) as fh:
            for line in fh:
                parts = line.rstrip("\n").split(":", 2)
                if len(parts) == 3:
                    for controller in parts[1].split(",") if parts[1] else [""]:
                        groups[controller] = parts[2]
    except OSError:
        pass
    return groups


def read_cpu_s(meter):
    """The CPU (s) a cgroup meter's group has used so far; 0.0 for ``"rusage"``'s (see ``_rusage_s``)."""
    if meter.source != "cgroup":
        return 0.0
    with open(meter.usage) as fh:
        text = fh.read()
    if meter.usage.endswith("cpuacct.usage"):
        return int(text) / 1e9
    return int(re.search(r"^usage_usec (\d+)$", text, re.M).group(1)) / 1e6


def _rusage_s():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _joiner(meter):
    """The ``preexec_fn`` that moves a child into the meter's group before it runs anything (None for rusage)."""
    if meter.source != "cgroup":
        return None
    procs = os.path.join(meter.path, "cgroup.procs")

    def join():
        with open(procs, "w") as fh:
            fh.write(str(os.getpid()))
    return join


def choose_meter(root=CGROUP_ROOT, proc_cgroup="/proc/self/cgroup", name=None):
    """A ``Meter``: a new cgroup under this process's own (v1 ``cpuacct``, then v2), proved by moving a process into
    it; else ``"rusage"`` with each group's reason in its note.

    Parameters
    ----------
    root : str
        Where the cgroup file systems are mounted (v1 ``root/cpuacct``; v2 ``root`` or ``root/unified``).
    proc_cgroup : str
        The file that names this process's groups.
    name : str, optional
        The new group's name; ``dalembert-suite-<pid>`` by default.
    """
    name = name or f"dalembert-suite-{os.getpid()}"
    own = _own_groups(proc_cgroup)
    why = []
    for version, mount, key, usage in (("v1", os.path.join(root, "cpuacct"), "cpuacct", "cpuacct.usage"),
                                        ("v2", root, "", "cpu.stat"),
                                        ("v2", os.path.join(root, "unified"), "", "cpu.stat")):
        marker = "cpuacct.usage" if version == "v1" else "cgroup.controllers"
        if not os.path.exists(os.path.join(mount, marker)):
            why.append(f"{mount}: no cgroup {version} there")
            continue
        if key not in own:
            why.append(f"{mount}: {proc_cgroup} names no {version} group of this process")
            continue
        path = os.path.join(mount, own[key].lstrip("/"), name)
        try:
            os.mkdir(path)
        except OSError as e:
            why.append(f"{path}: cannot be made ({e.strerror})")
            continue
        meter = Meter("cgroup", path, os.path.join(path, usage),
                      f"cgroup {version} {path}: every process the suite starts, nothing else")
        if not os.path.exists(meter.usage) or not os.path.exists(os.path.join(path, "cgroup.procs")):
            why.append(f"{mount}: not a cgroup file system (a new group there has no {usage})")
            shutil.rmtree(path, ignore_errors=True)  # a plain directory: no group to release
            continue
        try:
            subprocess.run(["true"], preexec_fn=_joiner(meter), check=True)
            read_cpu_s(meter)
        except (OSError, subprocess.SubprocessError, ValueError, AttributeError) as e:
            why.append(f"{path}: a process cannot join it or its usage cannot be read ({e})")
            release(meter)
            continue
        return meter
    return Meter("rusage", note="getrusage(RUSAGE_CHILDREN): UNDERCOUNTS — only processes their parents waited for "
                                "(not a pool's forkserver children nor orphans); no cgroup: " + "; ".join(why))


def members(meter):
    """The pids in the meter's group now ([] for rusage, or once the group is gone)."""
    if meter.source != "cgroup":
        return []
    try:
        with open(os.path.join(meter.path, "cgroup.procs")) as fh:
            return [int(p) for p in fh.read().split()]
    except OSError:
        return []


def settle(meter, linger_s=LINGER_S):
    """Waits up to ``linger_s`` for the group's processes to exit, then ends the rest (SIGTERM, then SIGKILL): the
    number that had to be ended."""
    deadline = time.monotonic() + linger_s
    while members(meter) and time.monotonic() < deadline:
        time.sleep(0.1)
    ended = len(members(meter))
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for pid in members(meter):
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + 2.0
        while members(meter) and time.monotonic() < deadline:
            time.sleep(0.1)
    return ended


def release(meter):
    """Ends what is left in the meter's group and removes the group (nothing for rusage, or once it is gone)."""
    if meter.source != "cgroup" or not os.path.isdir(meter.path):
        return
    settle(meter, linger_s=0.0)
    try:
        os.rmdir(meter.path)
    except OSError as e:
        print(f"(cgroup {meter.path} left: {e.strerror})", file=sys.stderr)


# -- the run ---------------------------------------------------------------------------------------------------------

def checkout():
    """The repository root this benchmark lives in (where the README's test command runs)."""
    return os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def commit(root):
    """``(HEAD's hash, whether tracked files differ from it)``; ``(None, None)`` outside git."""
    try:
        head = subprocess.run(["git", "-C", root, "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
        diff = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                              capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return None, None
    return head.stdout.strip(), bool(diff.stdout.strip())


def seed_cache(cache):
    """Copies the Pinocchio stepper libraries from the user's cache into ``cache``; the names copied."""
    from dalembert.cache import cache_dir

    names = []
    for lib in sorted(glob.glob(os.path.join(cache_dir(), STEPPER_GLOB))):
        shutil.copy2(lib, cache)
        names.append(os.path.basename(lib))
    return names


def suite_env(cache, hook_dir, log_dir):
    """The suite's environment: this one with ``DALEMBERT_CACHE``, the hook first on ``PYTHONPATH`` and its log
    directory."""
    path = os.pathsep.join(p for p in (hook_dir, os.environ.get("PYTHONPATH", "")) if p)
    return dict(os.environ, DALEMBERT_CACHE=cache, PYTHONPATH=path, **{JAXLOG_ENV: log_dir})


def run_suite(argv, env, log, meter):
    """Runs pytest (``argv`` after the interpreter) in the checkout, its output into ``log``: ``(rc, wall s, CPU s,
    processes ended after it)``."""
    before = read_cpu_s(meter) if meter.source == "cgroup" else _rusage_s()
    t0 = time.perf_counter()
    with open(log, "w") as out:
        rc = subprocess.run([sys.executable, *argv], cwd=checkout(), env=env, stdin=subprocess.DEVNULL, stdout=out,
                            stderr=subprocess.STDOUT, preexec_fn=_joiner(meter)).returncode
    wall = time.perf_counter() - t0
    if meter.source == "cgroup":
        ended = settle(meter)  # the processes that outlive pytest: their CPU until they exit is the suite's too
        return rc, wall, read_cpu_s(meter) - before, ended
    return rc, wall, _rusage_s() - before, 0


def _logs(log_dir):
    for path in sorted(glob.glob(os.path.join(log_dir, "*.log"))):
        with open(path, errors="replace") as fh:
            yield fh.read()


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[:argv.index("--")] if "--" in argv else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                epilog="-- PYTEST ARGS: after the README's command (-- -n 1: the last -n wins; -- "
                                       "tests/test_x.py: those files only)")
    p.add_argument("--jax-cache", choices=("cold", "warm"), default=None,
                   help="cold: a fresh cache but for the Pinocchio stepper (default); warm: the suite run once into "
                        "it first, untimed")
    p.add_argument("--cache", metavar="DIR", help="DALEMBERT_CACHE as it is, neither emptied nor seeded")
    p.add_argument("--json", metavar="FILE", help="write the figures as JSON")
    p.add_argument("--log", metavar="FILE", help="keep pytest's whole output (of the timed run) in FILE")
    args = p.parse_args(argv)
    if args.cache and args.jax_cache:
        p.error(f"--cache {args.cache}: runs on that cache as it is — give --cache or --jax-cache, not both")
    if args.cache and not os.path.isdir(args.cache):
        p.error(f"--cache: {args.cache} is not a directory — give a cache directory an earlier run filled")
    mode = "given" if args.cache else (args.jax_cache or "cold")
    root = checkout()
    head, dirty = commit(root)
    pytest = [*PYTEST, *DURATIONS, *extra]

    with tempfile.TemporaryDirectory(prefix="dalembert-suite-") as tmp:
        cache = os.path.abspath(args.cache) if args.cache else os.path.join(tmp, "cache")
        hook_dir, log_dir = os.path.join(tmp, "hook"), os.path.join(tmp, "jaxlog")
        for d in (hook_dir, log_dir) + (() if args.cache else (cache,)):
            os.makedirs(d)
        with open(os.path.join(hook_dir, "sitecustomize.py"), "w") as fh:
            fh.write(HOOK)
        if not args.cache:
            seeded = seed_cache(cache)
            print(f"cache {cache}: " + (f"{len(seeded)} Pinocchio stepper libraries copied" if seeded else
                                        "NO Pinocchio stepper to copy: the suite compiles it (~2 CPU-min)"), flush=True)
        if mode == "warm":
            print("warming the cache: the suite once, untimed ...", flush=True)
            warm_dir = os.path.join(tmp, "jaxlog-warm")
            os.makedirs(warm_dir)
            rc, wall, _, _ = run_suite(pytest, suite_env(cache, hook_dir, warm_dir), os.path.join(tmp, "warm.txt"),
                                       Meter("rusage"))
            print(f"  (pytest rc {rc}, {wall:.0f} s)", flush=True)
        meter = choose_meter()
        print(f"CPU from {meter.note}", flush=True)
        load0 = os.getloadavg()[0]
        print(f"running: {os.path.basename(sys.executable)} {' '.join(pytest)}  (in {root}, load {load0:.2f})",
              flush=True)
        log = args.log or os.path.join(tmp, "pytest.txt")
        try:
            rc, wall, cpu, ended = run_suite(pytest, suite_env(cache, hook_dir, log_dir), log, meter)
        finally:
            release(meter)  # (a Ctrl-C too leaves no group behind)
        load1 = os.getloadavg()[0]
        with open(log, errors="replace") as fh:
            text = fh.read()
        jax = jax_compiles(_logs(log_dir))

    tests = outcomes(text)
    files = file_seconds(text)
    for line in text.splitlines():
        if line.startswith(("FAILED ", "ERROR ")):
            print(line)
    counts = ", ".join(f"{tests.get(k, 0)} {k}" for k in ("passed", "failed", "skipped"))
    more = ", ".join(f"{n} {k}" for k, n in tests.items() if k not in ("passed", "failed", "skipped", "warnings"))
    print(f"\nsuite at {(head or '?')[:12]}{' (dirty)' if dirty else ''}, cache {mode}: {counts}"
          f"{', ' + more if more else ''} (pytest rc {rc})")
    print(f"wall {wall:.1f} s, CPU {cpu:.1f} s ({meter.source}), CPU/wall {cpu / wall:.2f}; "
          f"{os.cpu_count()} cores, load {load0:.2f} at the start, {load1:.2f} at the end"
          + (f"; {ended} processes outlived it by {LINGER_S:.0f} s and were ended" if ended else ""))
    if meter.source != "cgroup":
        print(f"  CPU UNDERCOUNTED: {meter.note}")
    print(f"JAX: {jax.compiles} XLA compiles ({jax.cache_hits} from the persistent cache), "
          f"{jax.compile_wall_s:.1f} s of compile wall time")
    total = sum(files.values())
    print(f"top {TOP} test files of {len(files)} by test time (setup + call + teardown, summed over the workers; "
          f"{total:.1f} s in all):")
    for name, s, share in top_files(files):
        print(f"{s:>9.1f} s {100 * share:>5.1f} %  {name}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"schema": 1, "commit": head, "dirty": dirty, "cpu_s": cpu, "wall_s": wall,
                       "cpu_source": meter.source, "cpu_note": meter.note,
                       "jax": {"compiles": jax.compiles, "compile_wall_s": jax.compile_wall_s,
                               "cache_hits": jax.cache_hits},
                       "files": dict(sorted(files.items(), key=lambda kv: -kv[1])), "tests": tests, "cache": mode,
                       "pytest_rc": rc, "load": [load0, load1], "cores": os.cpu_count()}, fh, indent=1)
    return rc


if __name__ == "__main__":
    sys.exit(main())
