"""The record of one (case, engine, settings) run: ``RunResult``.

A failure is data, not an exception that stops the suite (like scipy's
``OdeResult``): every run ends in one of ``STATUSES`` with a message.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["STATUSES", "Cost", "RunResult"]

# ok: finished; unsupported: the engine cannot represent the scene (reason in
# message); diverged: NaN/inf or blow-up (time in message); failed: an error;
# timeout: stopped at the per-run time limit.
STATUSES = ("ok", "unsupported", "diverged", "failed", "timeout")


@dataclass(frozen=True)
class Cost:
    """What a run cost: stepping wall time (s, model build excluded), steps, RHS evaluations."""

    wall_s: float = float("nan")
    n_steps: int = 0
    n_rhs: int = 0


@dataclass(frozen=True, eq=False)
class RunResult:
    """Outcome of one run.

    Attributes
    ----------
    status : str — one of ``STATUSES``
    message : str — why, for anything but ``ok``
    trajectory : Trajectory or None
    cost : Cost
    audit : dict — effects read back from the engine (gravity, loads, constraints, ...)
    provenance : dict — engine version, harness commit, machine, timestamp
    """

    status: str
    message: str = ""
    trajectory: object = None
    cost: Cost = field(default_factory=Cost)
    audit: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"status: unknown {self.status!r} — use one of {STATUSES}")

    @property
    def ok(self):
        return self.status == "ok"
