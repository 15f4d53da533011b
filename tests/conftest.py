"""Fixtures shared by the test modules."""

import os

import pytest

from dalembert.harness import threads


def pytest_configure(config):
    """pytest-xdist's workers share the cores as a matrix's workers do (``dalembert.harness.threads``): each
    one's BLAS and OpenMP pools get its share, through the variables the libraries read when they load, set
    here before the workers start (they inherit them; a value the user set is kept)."""
    n = getattr(config.option, "numprocesses", None)
    if isinstance(n, int) and n > 1 and "PYTEST_XDIST_WORKER" not in os.environ:
        for var in threads.VARIABLES:
            os.environ.setdefault(var, str(threads.per_worker(n)))


@pytest.fixture(scope="session")
def shared_dir(tmp_path_factory, worker_id):
    """A directory every pytest-xdist worker of this session sees (each worker's base temporary directory
    is a child of one; ``master`` when the session is not distributed). For ``truths.shared_truth``."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent


def pytest_collection_modifyitems(config, items):
    """Tests marked ``long`` (each takes >= ~10 s on 2 cores: an engine's contract over every case, MJX
    compilations, matrices through the command line) run first, so that pytest-xdist's workers, handed
    tests in collection order, do not end the session with one of them running alone.

    Tests marked ``leaves_threads`` run last: a Python thread they leave in the process (an in-process Dask
    client leaves distributed's offload thread) makes every later matrix in it start its workers from a
    forkserver (``harness.pool``: forking a process with threads is unsafe), each of them importing its
    engines again instead of sharing the test process's (~1 s more per matrix)."""
    def order(item):
        return 2 if item.get_closest_marker("leaves_threads") else 0 if item.get_closest_marker("long") else 1

    items.sort(key=order)  # stable: the order otherwise kept
