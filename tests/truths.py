"""Each slow truth once per test session, shared by the tests and the xdist workers that need it.

A truth from the reference solver at its tight tolerance takes seconds (``andrews_squeezer`` ~12 s,
``bricard`` ~6 s on one core), and both a case's own test module and the case contract
(``test_case_contract.py``) need it, often in different xdist workers. ``shared_truth`` computes it once per
session: the first worker to ask computes it under a file lock and leaves it in the session's shared
temporary directory; a worker asking later loads it, one asking meanwhile waits for it (never longer than
computing it itself). This is pytest-xdist's documented pattern for a session fixture run once; its
``xdist_group`` marks cannot serve here, since pytest 9 ignores the node ids xdist 3.8 rewrites for them.
"""

import fcntl
import pickle

from dalembert.reference import truth

__all__ = ["shared_truth"]

_TRUTHS = {}  # this process's, by (case name, version)


def shared_truth(case, shared_dir):
    """``reference.truth(case)``, computed once per case version in the session.

    Parameters
    ----------
    case : Case — ``Case.version`` hashes its scene, horizon, sample times and parameters: a case made
        otherwise is another truth
    shared_dir : pathlib.Path — a directory every worker of the session sees (the ``shared_dir`` fixture)
    """
    key = (case.name, case.version)
    if key not in _TRUTHS:
        path = shared_dir / f"truth-{case.name}-{case.version}.pickle"
        with open(path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
            if path.exists():
                _TRUTHS[key] = pickle.loads(path.read_bytes())
            else:
                _TRUTHS[key] = truth(case)
                path.write_bytes(pickle.dumps(_TRUTHS[key]))
    return _TRUTHS[key]
