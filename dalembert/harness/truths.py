"""Each case of a matrix, once per version, before any run: its record and its truth.

The store then carries every case as it was run (``dalembert.case.CaseRecord``:
scene, parameters, tolerances with reasons, conserved quantities, floor) and its
truth at the sample times; workers are handed the truth instead of recomputing it,
and reports read both from the store.
"""

from __future__ import annotations

__all__ = ["prepare_cases", "truth_source"]


def truth_source(case):
    """Where the truth of ``case`` comes from, as stored with its record."""
    from dalembert.reference import truth_settings

    return "closed form" if case.exact is not None else f"reference solver, {truth_settings(case.scene).label()}"


def prepare_cases(specs, store):
    """Store the record and truth of each (case, version) of ``specs`` not yet in ``store``.

    Returns ``{(case, version): truth trajectory}`` for the workers.
    """
    from dalembert.case import CaseRecord, make_case
    from dalembert.reference import truth

    truths = {}
    for name, params, version in sorted({(s.case, s.params, s.case_version) for s in specs}):
        if not store.has_case(name, version) or store.truth(name, version) is None:
            case = make_case(name, **dict(params))
            if case.version != version:
                raise ValueError(f"case {name!r}: the matrix was made for version {version}, the code now makes "
                                 f"{case.version} — start a new matrix")
            store.write_case(CaseRecord.from_case(case, truth_source(case)), truth(case))
        truths[(name, version)] = store.truth(name, version)
    return truths
