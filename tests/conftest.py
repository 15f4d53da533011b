"""Fixtures shared by the test modules."""

import pytest


@pytest.fixture(scope="session")
def shared_dir(tmp_path_factory, worker_id):
    """A directory every pytest-xdist worker of this session sees (each worker's base temporary directory
    is a child of one; ``master`` when the session is not distributed). For ``truths.shared_truth``."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent
