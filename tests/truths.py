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

``contract_case`` is a registered case as the case contract checks it, and ``shared_truth_from`` the truth of a
case shortened below it, as the first samples of the contract's (``flyball_governor`` over 0.5 s in
``test_hard_cases.py``: 1.5 s of Radau spared).
"""

import dataclasses
import fcntl
import pickle

import numpy as np

from dalembert import testing
from dalembert.case import load_cases
from dalembert.reference import truth
from dalembert.trajectory import Trajectory

__all__ = ["shared_truth", "shared_reference", "contract_case", "shared_truth_from"]

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


def contract_case(name):
    """The registered case ``name`` as the case contract (``test_case_contract.py``) checks it: a hard one shortened
    to ``testing.HARD_HORIZON``, never lengthened (``robot_free_fall``'s own horizon is 1 s), the others as
    registered."""
    factory = load_cases()[name]
    horizon = testing.contract_horizon(factory)
    return factory() if horizon is None else factory(t_final=horizon)


def shared_truth_from(case, longer, shared_dir):
    """The truth of ``case`` as the first samples of ``longer``'s (``shared_truth``), where ``longer`` is the same
    case over a longer horizon, sampled at the same times up to ``case``'s last (the same integrator at the same
    tolerance: its samples there are the truth's to its accuracy; measured on ``flyball_governor`` over 0.5 s, 1e-13
    from a truth computed over 0.5 s); else ``case``'s own ``shared_truth``."""
    n = len(case.times)
    same_case = repr({**case.params, "t_final": None}) == repr({**longer.params, "t_final": None})
    if not same_case or case.name != longer.name or not np.array_equal(np.asarray(longer.times)[:n], case.times):
        return shared_truth(case, shared_dir)
    return _first_samples(shared_truth(longer, shared_dir), n)


def _first_samples(trajectory, n):
    """``trajectory``'s first ``n`` samples (every series is sample-major)."""
    def cut(states):
        return dataclasses.replace(states, **{f.name: getattr(states, f.name)[:n] for f in dataclasses.fields(states)
                                              if getattr(states, f.name) is not None})

    return Trajectory(trajectory.t[:n], {k: cut(b) for k, b in trajectory.bodies.items()},
                      {k: cut(j) for k, j in trajectory.joints.items()},
                      {k: np.asarray(v)[:n] for k, v in trajectory.extras.items()})
