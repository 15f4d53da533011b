"""What a worker sends back of a run: its record always, its trajectory only where the store keeps it.

A store keeps every run's trajectory, those its report may draw, or none (``dalembert.trajectory_store``'s
``KEEPS``, the manifest's ``trajectories``); the parent drops the rest as it writes (``Trajectories.write``).
A worker told the same choice (``Sent``, with each job) does not build a dropped trajectory's ``.npz`` bytes,
pickle them or send them: a map of 1e4 probes kept ``none`` or ``drawn`` otherwise moves every probe's
trajectory to the parent to be thrown away. The record is the same either way: its errors, drifts and
checks are computed from the trajectory in the worker; only its bytes stay there.

For ``drawn`` the worker applies the parent's own rule (``reports.drawn.may_be_drawn``), on the manifest's
case versions (``Sent.of``) and the run's case as built in the worker (the same case version as the store's
record of it: a run whose case changed fails before it has a trajectory).

Measured (2 shared cores, load 3 to 6, alternated in one sitting; ``benchmarks.map``'s ``--probes`` map kept
``none``): 1042 probes on 2 local workers sent 3.3 MB of trajectories before (3.1 kB a probe: 6 samples), none
after; 311 probes on a 2-worker ``LocalCluster`` 0.98 MB, none after; the same map at a 20-s horizon (1083 probes,
45 kB a probe) 49 MB, none after. Neither wall time (34 to 44 s, 47 to 57 s, 145 to 172 s) nor the parent's or
the workers' CPU moved beyond the noise between repeats: at these sizes building and pickling a trajectory is
well under a millisecond of a probe's cost; what is saved is the bytes, which grow with a map's trajectories.
"""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.trajectory_store import ALL, DRAWN, KEEPS, NONE

__all__ = ["Sent", "told"]


@dataclass(frozen=True)
class Sent:
    """Which trajectories a worker sends (module docstring).

    Parameters
    ----------
    keep : str
        One of ``trajectory_store.KEEPS``: what the store keeps.
    versions : tuple of (str, str)
        For ``drawn``: ``(case, case_version)`` pairs of the manifest's specs, as ``may_be_drawn`` counts them
        (at most ``DETAILED_VERSIONS + 1`` per case: it compares a case's count with ``DETAILED_VERSIONS`` only,
        and a map's thousands of versions need not travel with every job).
    """

    keep: str = ALL
    versions: tuple = ()

    def __post_init__(self):
        if self.keep not in KEEPS:
            raise ValueError(f"Sent.keep: {self.keep!r} is not a choice — use one of {', '.join(KEEPS)}")

    @classmethod
    def of(cls, keep, specs=()):
        """What a worker sends for a store that keeps ``keep``, whose manifest's specs (dicts) are ``specs`` (read
        for ``drawn`` only)."""
        if keep != DRAWN:
            return cls(keep)
        from dalembert.reports.drawn import DETAILED_VERSIONS

        versions = {}
        for s in specs:
            seen = versions.setdefault(s["case"], [])
            if len(seen) <= DETAILED_VERSIONS and s["case_version"] not in seen:
                seen.append(s["case_version"])
        return cls(keep, tuple((case, v) for case, vs in versions.items() for v in vs))

    def wants(self, record, case_of):
        """Whether the store keeps the trajectory of the run of ``record`` (a ``RunRecord``); ``case_of(name,
        version)`` gives its case (read only for ``drawn``, and only where the loop-closure hazard may read it)."""
        if self.keep == NONE:
            return False
        if self.keep == ALL:
            return True
        from dalembert.reports.drawn import may_be_drawn

        return may_be_drawn([{"case": c, "case_version": v} for c, v in self.versions], case_of)(record)


def told(store, specs):
    """The ``Sent`` of ``store`` (its manifest's ``specs``: dicts) for its workers, the parent's own rule set beside
    it: for ``drawn``, ``store.kept().drawable`` (``Trajectories.write`` drops what a caller's worker still sends)."""
    keep = store.kept().keep
    if keep == DRAWN:
        from dalembert.reports.drawn import may_be_drawn

        store.kept().drawable = may_be_drawn(specs, store.case)
    return Sent.of(keep, specs)
