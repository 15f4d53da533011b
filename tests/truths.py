"""Each slow truth once per test session, shared by the tests and the xdist workers that need it.

A truth from the reference solver at its tight tolerance takes seconds (``andrews_squeezer`` ~12 s,
``bricard`` ~6 s on one core), and both a case's own test module and the case contract
(``test_case_contract.py``) need it, often in different xdist workers. ``shared_truth`` computes it once per
session: the first worker to ask computes it under a file lock and leaves it in the session's shared
temporary directory; a worker asking later loads it, one asking meanwhile waits for it (never longer than
computing it itself). This is pytest-xdist's documented pattern for a session fixture run once; its
``xdist_group`` marks cannot serve here, since pytest 9 ignores the node ids xdist 3.8 rewrites for them.

``shared_reference`` does the same for the case contract's independent solution of a closed-form case (the
reference through a loop's singular positions: ~6 s of CPU for ``n_four_bar``), which
``test_reference_check.py`` also judges against the closed form.
"""

import fcntl
import pickle

from dalembert import testing
from dalembert.reference import truth

__all__ = ["shared_truth", "shared_reference"]

_SHARED = {}  # this process's, by (what, case name, version)
# the function itself, taken once here: the case contract hands ``shared_reference`` to ``testing`` in its place
_REFERENCE = testing._reference_through_singular_positions


def shared_truth(case, shared_dir):
    """``reference.truth(case)``, computed once per case version in the session.

    Parameters
    ----------
    case : Case — ``Case.version`` hashes its scene, horizon, sample times and parameters: a case made
        otherwise is another truth
    shared_dir : pathlib.Path — a directory every worker of the session sees (the ``shared_dir`` fixture)
    """
    return _shared("truth", truth, case, shared_dir)


def shared_reference(case, shared_dir):
    """``testing._reference_through_singular_positions(case)``: ``(label, trajectory)`` of the reference's
    DOP853 against a closed form (retried at the looser tolerance where it stops at a singular position),
    computed once per case version in the session; arguments as ``shared_truth``'s."""
    return _shared("reference", _REFERENCE, case, shared_dir)


def _shared(what, compute, case, shared_dir):
    """``compute(case)``, computed by the first worker to ask under a file lock and loaded by the others."""
    key = (what, case.name, case.version)
    if key not in _SHARED:
        path = shared_dir / f"{what}-{case.name}-{case.version}.pickle"
        with open(path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
            if path.exists():
                _SHARED[key] = pickle.loads(path.read_bytes())
            else:
                _SHARED[key] = compute(case)
                path.write_bytes(pickle.dumps(_SHARED[key]))
    return _SHARED[key]
