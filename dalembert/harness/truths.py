"""Each case of a matrix, once per version, before any run: its record and its truth.

The store then carries every case as it was run (``dalembert.case.CaseRecord``:
scene, parameters, tolerances with reasons, conserved quantities, floor) and its
truth at the sample times; workers are handed the truth instead of recomputing it,
and reports read both from the store.
"""

from __future__ import annotations

from collections import OrderedDict

__all__ = ["built_case", "prepare_cases", "truth_source", "build", "store_cases"]

# The cases a process keeps built: a matrix has a few dozen case variants at most, and a long-lived
# process (the Python API, a pool's worker) needs only the recent ones.
CASES_KEPT = 64
_BUILT = OrderedDict()  # (name, sorted params) -> (factory, Case, version)


def built_case(name, params=()):
    """The case ``name`` made with ``params`` ((key, value) pairs or a mapping), and its version.

    Built once per process and kept (``CASES_KEPT``): a run's case is asked for by the matrix's
    expansion, its truth, a resume's check and the run itself, and its version (a content hash of the
    whole case) is computed once with it. A case whose factory was registered anew is built again.

    Returns
    -------
    case : dalembert.case.Case
    version : str — ``case.version``
    """
    from dalembert.case import load_cases

    factory = load_cases()[name]  # KeyError with "did you mean" for an unknown name
    params = tuple(sorted(dict(params).items()))
    # keyed by each value's repr, not the value: 500 == 500.0 (and hash alike) but they make cases of different
    # versions (the version hashes the parameters as given), so a cache keyed by value handed one for the other
    key = (name, tuple((k, repr(v)) for k, v in params))
    hit = _BUILT.get(key)
    if hit is not None and hit[0] is factory:
        _BUILT.move_to_end(key)
        return hit[1], hit[2]
    case = factory(**dict(params))
    _BUILT[key] = (factory, case, case.version)
    while len(_BUILT) > CASES_KEPT:
        _BUILT.popitem(last=False)
    return case, _BUILT[key][2]


def truth_source(case):
    """Where the truth of ``case`` comes from, as stored with its record."""
    from dalembert.reference import truth_settings

    return "closed form" if case.exact is not None else f"reference solver, {truth_settings(case.scene).label()}"


def prepare_cases(specs, store):
    """Store the record and truth of each (case, version) of ``specs`` not yet in ``store``.

    Returns ``{(case, version): truth trajectory}`` for the workers.
    """
    from dalembert.case import CaseRecord
    from dalembert.identity import check_version
    from dalembert.reference import truth

    truths = {}
    for name, params, version in sorted({(s.case, s.params, s.case_version) for s in specs}):
        if not store.has_case(name, version) or store.truth(name, version) is None:
            case, now = built_case(name, params)
            changed = check_version(name, version, now, "the matrix was made for")
            if changed:
                raise ValueError(f"{changed} — start a new matrix")
            store.write_case(CaseRecord.from_case(case, truth_source(case)), truth(case))
        truths[(name, version)] = store.truth(name, version)
    return truths


def _finite(trajectory):
    """Whether every number of ``trajectory`` is finite."""
    import numpy as np

    arrays = [trajectory.t] + [a for b in trajectory.bodies.values()
                               for a in (b.position, b.quaternion, b.velocity, b.angular_velocity)]
    arrays += [a for j in trajectory.joints.values() for a in (j.q, j.v)]
    return all(np.isfinite(np.asarray(a, dtype=float)).all() for a in arrays)


def build(specs):
    """Each (case, version) of ``specs`` built with its truth, before any store is made (so that a
    case that cannot be computed refuses the matrix, not its first run): ``{(case, version): (Case,
    truth)}``, for ``store_cases``.

    Raises ValueError naming the case and its parameters when the case cannot be built or its truth
    computed or is not finite; numpy's warnings on the way (an overflow) are part of that message,
    not printed. A truth that comes out finite gives its warnings back as they were.
    """
    import warnings

    from dalembert.reference import truth
    from dalembert.scene import SceneError

    built = {}
    for name, params, version in sorted({(s.case, s.params, s.case_version) for s in specs}):
        given = ", ".join(f"{k}={v}" for k, v in params) or "its defaults"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RuntimeWarning)
            try:
                case, _ = built_case(name, params)
                made = truth(case)
                problem = None if _finite(made) else "its truth is not finite"
            except (ValueError, ArithmeticError, SceneError) as e:
                problem = f"its truth cannot be computed ({e})"
        numpy_said = sorted({str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)})
        if problem:
            raise ValueError(f"case {name!r} with {given}: {problem}"
                             + (f"; numpy: {'; '.join(numpy_said)}" if numpy_said else "")
                             + " — check the parameters (--param): the values are out of the case's range")
        for w in caught:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        built[(name, version)] = (case, made)
    return built


def store_cases(store, built):
    """Write what ``build`` made into ``store`` (each case's record and truth), so that the matrix's
    ``prepare_cases`` finds them there instead of computing them again."""
    from dalembert.case import CaseRecord

    for case, made in built.values():
        if not store.has_case(case.name, case.version) or store.truth(case.name, case.version) is None:
            store.write_case(CaseRecord.from_case(case, truth_source(case)), made)
