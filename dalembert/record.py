"""The record of one (case, engine, settings) run, ``RunRecord``, and its one row schema.

A failure is data, not an exception that stops the suite (like scipy's
``OdeResult``): every run ends in one of ``STATUSES`` with a message, and its
verdict, judged once when it ran (``dalembert.judge``), is stored with it.

``RunRecord.to_row()`` and ``RunRecord.from_row()`` are the only place a column
name is spelled; every reader (report, compare, export, tests) goes through them.
A row is strict JSON: non-finite numbers are stored as null (the status says why).

Columns (``SCHEMA_VERSION`` 4):

==============  ==================================================================
identity        ``key``, ``schema_version``, ``case``, ``case_version``, ``params``
                (JSON), ``param_<name>`` per given case parameter (a number, or a
                vector as JSON: swept values filter like any column), ``engine``,
                ``engine_version``, ``adapter_distribution`` and ``adapter_version`` (the
                installed distribution that provides the adapter: ``dalembert`` for a built-in,
                the plugin's package for an entry point), ``integrator``, ``integrator_order``
                (the order of accuracy the integrator declares, ``IntegratorSpec.order``; null when
                none), ``dt`` (s), ``rtol``, ``atol``, ``options`` (JSON), ``settings`` (a label)
outcome         ``status``, ``message``, ``t_final`` (s), ``t_diverged`` (s),
                ``traceback``
cost            ``build_s``, ``wall_s_median``, ``wall_s_min``, ``wall_s_max`` (stepping
                alone), ``wall_s_repeats`` (JSON: every timed repeat's stepping time, s, in the
                order run, so a later ``compare`` can test significance), ``repeats``, ``n_steps``, ``n_rhs``, ``overhead_s``, ``readback_s``,
                ``stepping_total_s``, ``worker_s`` (all s), ``concurrent`` (runs in
                flight), ``load_start``, ``load_end`` (1-minute load average), ``batch_size``
                (worlds stepped in one engine call), ``batch_wall_s`` (the batch's stepping time, s),
                ``world_steps_per_s`` (the batch's throughput), ``device`` (where it stepped)
errors          ``err_<quantity>_max``, ``err_<quantity>_final`` (``dalembert.errors.QUANTITIES``)
drifts          ``drift_<name>``, ``drift_rate_<name>`` (1/s) per conserved quantity,
                ``growth_<name>`` (its change in units of its scale on the true motion), built-in or
                declared by the case (``dalembert.case.Invariant``: its label is in the store's case record)
checks          ``orthonormality``, ``quaternion_norm``, ``joint_residual`` (maxima)
judgement       ``within_tolerance``, ``beyond_tolerance`` and ``not_measured`` (names,
                space-separated), ``verdict``, ``verdict_reason``
engine          ``audit`` (JSON), ``model`` (text), ``provenance`` (JSON: host, pid, threads:
                the width its BLAS and OpenMP pools were given; libraries: the version of each
                library loaded where it ran, ``{distribution: version}``)
files           ``trajectory`` (path relative to the store)
==============  ==================================================================

Schema 1 (stores written before the schema was versioned) has the same columns
without ``schema_version``, ``verdict``, ``verdict_reason`` and ``provenance``;
``from_row`` reads it with an empty verdict, so ``compare`` works across the change.
Schemas 1 and 2 have no ``wall_s_repeats``: ``from_row`` reads them with none (an empty tuple), the
median, min and max being all they kept.
Schemas 1 to 3 have no ``adapter_distribution``, ``adapter_version``, ``integrator_order`` nor
``not_measured``: ``from_row`` reads them as "" (not recorded), None and no names; their
``within_tolerance`` reads as it was judged then (a
bound whose quantity the run did not report counted as within).
Rows written before batched worlds (``dalembert.harness.batches``) have no ``batch_size``, ``batch_wall_s``,
``world_steps_per_s`` nor ``device``: ``from_row`` reads them as one world, NaN, NaN and "" (not recorded),
under the same schema (the columns are optional, their defaults what those rows ran).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, fields, replace

from dalembert.judge import Judgement
from dalembert.settings import Settings, option_text

__all__ = ["SCHEMA_VERSION", "READABLE_SCHEMAS", "STATUSES", "BAD_STATUSES", "CHECKS", "Cost", "RunRecord",
           "SchemaError", "UNJUDGED"]

SCHEMA_VERSION = 4
READABLE_SCHEMAS = (1, 2, 3, 4)

# ok: finished; unsupported: the engine cannot represent the scene (reason in
# message); diverged: NaN/inf or blow-up (time in message); failed: an error;
# timeout: stopped at the per-run time limit.
STATUSES = ("ok", "unsupported", "diverged", "failed", "timeout")
# The statuses that are findings against an engine (``--strict`` exits 1 on them).
BAD_STATUSES = ("failed", "diverged", "timeout")
# Checks of the attitude representation and the joints, computed for every ok run.
CHECKS = ("orthonormality", "quaternion_norm", "joint_residual")

_NAN = float("nan")
_COUNTS = ("repeats", "n_steps", "n_rhs", "concurrent", "batch_size")  # the integer fields of Cost
_TEXTS = ("device",)  # the text fields of Cost


class _cached:
    """A derived value computed on its first read and kept in the instance's ``__dict__`` (later reads find it there,
    never calling this): ``functools.cached_property`` without the lock Python 3.11's takes on every first read (1.5 us
    each, profiled: longer than computing the value; a report reads five of these of each of 1e5-1e6 records). Two threads
    reading it first at once both compute it, to the same value."""

    def __init__(self, func):
        self.func, self.name, self.__doc__ = func, func.__name__, func.__doc__

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, instance, owner=None):
        if instance is None:
            return self
        value = instance.__dict__[self.name] = self.func(instance)
        return value


# The judgement of a record made without one (schema 1 stores kept no verdict).
UNJUDGED = Judgement(beyond=(), verdict="", reason="", within_tolerance=None)


class SchemaError(ValueError):
    """A row or a store written with a schema this version of dalembert cannot read."""


@dataclass(frozen=True)
class Cost:
    """What a run cost. Times in s; the stepping times exclude building the model.

    Attributes
    ----------
    build_s : building the engine model
    wall_s_median, wall_s_min, wall_s_max : stepping wall time over the timed repeats
    wall_s_repeats : tuple of float — every timed repeat's stepping wall time, in the order run (empty
        in stores of schema 1 and 2, which kept only the three figures above)
    repeats : timed repeats (after one untimed warm-up)
    n_steps, n_rhs : steps and right-hand-side evaluations of one run
    overhead_s : median time per timed repeat of ``Adapter.run`` outside its stepping (the
        read-back is not in it: it runs once per run, ``Outcome.read_back``)
    readback_s : the read-back, once per run: the adapter turning the engine's sampled states into
        body terms (reactions cost a dynamics evaluation per sample in some engines)
    stepping_total_s : stepping time of the warm-up and every repeat
    worker_s : wall time of the whole run in its worker
    concurrent : runs in flight on this machine's pool when this one started, itself included
        (its timings compete with that many; 1 with ``--jobs 1``)
    load_start, load_end : the machine's 1-minute load average when the run started and ended
        (a load above the cores by more than a matrix's own footprint means the timings were shared with
        other work: ``reports.timing``)
    batch_size : worlds stepped at once in the engine call that made this run (a ``--batch`` batch,
        ``dalembert.harness.batches``, or copies an adapter stepped beside it, MuJoCo Warp's ``worlds``; 1: the run
        stepped alone). Where it is above 1, ``wall_s_*``, ``overhead_s`` and ``stepping_total_s`` are this world's
        share of the batch's (its time over ``batch_size``: per world), never a single world's latency; a
        ``--batch`` run's ``build_s`` and ``worker_s`` are its share too
    batch_wall_s : the batch's stepping wall time (median over the timed repeats), every world; NaN for a run
        stepped alone
    world_steps_per_s : the batch's throughput, world-steps per second (``batch_size * n_steps / batch_wall_s``);
        NaN for a run stepped alone
    device : where the engine stepped (``cpu``, ``cuda:0``; "": not recorded)
    """

    build_s: float = _NAN
    wall_s_median: float = _NAN
    wall_s_min: float = _NAN
    wall_s_max: float = _NAN
    wall_s_repeats: tuple = ()
    repeats: int = 0
    n_steps: int = 0
    n_rhs: int = 0
    overhead_s: float = _NAN
    readback_s: float = _NAN
    stepping_total_s: float = _NAN
    worker_s: float = _NAN
    concurrent: int = 0
    load_start: float = _NAN
    load_end: float = _NAN
    batch_size: int = 1
    batch_wall_s: float = _NAN
    world_steps_per_s: float = _NAN
    device: str = ""


@dataclass(frozen=True, eq=False)
class RunRecord:
    """One (case, engine, settings) run as stored.

    Attributes
    ----------
    key : str — the run's file key in the store
    case, case_version : str — the case and the content hash of the version run
    params : dict — the case parameters given (the rest are the factory's defaults)
    engine, engine_version : str
    adapter_distribution, adapter_version : str — the installed distribution that provides the adapter and its
        version (``dalembert.adapters.registry.adapter_distribution``; "" when not recorded: schemas 1 to 3, or an
        adapter registered from a module no distribution provides)
    settings : Settings — integrator, fixed step ``dt`` (s) or tolerances ``rtol``/``atol``, engine options
    integrator_order : int or None — the order of accuracy the engine declares for the integrator when the run ran
        (``IntegratorSpec.order``; None when it declares none, and in stores of schemas 1 to 3)
    status : str — one of ``STATUSES``; message : str — why, for anything but ``ok``
    t_final : float — the case's horizon, s; t_diverged : float or None — first non-finite sample, s
    cost : Cost
    errors : dict quantity -> (max over the horizon, at the final time), units of
        ``dalembert.errors.QUANTITIES``; NaN max when the run is not finite
    drifts : dict conserved name -> drift (``dalembert.invariants.CONSERVED``, or a name the case declares)
    drift_rates : dict conserved name -> slope of the relative change, 1/s (energy-like ones)
    growths : dict conserved name -> change in units of its scale on the truth (blow-ups show here)
    checks : dict name -> float — ``CHECKS``
    judgement : Judgement — the tolerances exceeded (``beyond``), the ``verdict`` and its ``reason``,
        ``within_tolerance`` (``dalembert.judge``; stored as the ``verdict_reason`` column and the others)
    audit : dict — effects read back from the engine; model : str — its model, as text
    provenance : dict — where it ran (host, pid), its BLAS/OpenMP pools' width (threads, None when not set) and
        the libraries loaded where it ran (libraries: ``{distribution: version}``; none for a run its worker
        did not finish)
    trajectory : str — path of its trajectory in the store, "" when none
    traceback : str — for failed runs
    schema_version : int
    """

    key: str
    case: str
    case_version: str
    engine: str
    settings: Settings
    params: dict = field(default_factory=dict)
    status: str = "failed"
    message: str = ""
    engine_version: str = ""
    adapter_distribution: str = ""
    adapter_version: str = ""
    integrator_order: int | None = None
    t_final: float = _NAN
    t_diverged: float | None = None
    cost: Cost = field(default_factory=Cost)
    errors: dict = field(default_factory=dict)
    drifts: dict = field(default_factory=dict)
    drift_rates: dict = field(default_factory=dict)
    growths: dict = field(default_factory=dict)
    checks: dict = field(default_factory=dict)
    judgement: Judgement = UNJUDGED
    audit: dict = field(default_factory=dict)
    model: str = ""
    provenance: dict = field(default_factory=dict)
    trajectory: str = ""
    traceback: str = ""
    schema_version: int = SCHEMA_VERSION

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"status: unknown {self.status!r} — use one of {STATUSES}")

    # -------------------------------------------------------------- derived
    # A record keeps at most one derived value in its ``__dict__`` (``cost_per_sim_s``): with its 28 fields that is the
    # most CPython 3.11 keeps in a dict that shares its keys with every other record's (29: 288 bytes a record; one more
    # and each record's dict is its own, 1584 bytes: 1.3 GB more for a map of 1e6 runs). What a record derives from its
    # settings is kept once per ``Settings`` instead (``_settings_derived``: records read together share theirs).
    @property  # (asked of every run by most sections: 1e6 times for 1e5 runs; a comparison, not kept)
    def ok(self):
        return self.status == "ok"

    @property
    def settings_label(self):
        """``Settings.label()`` of the run: ``rk4 dt=0.001``, ``dop853 rtol=1e-09 atol=1e-09``, options appended."""
        return self.settings.label()

    @property  # (asked of every run a hazard names, for what they share)
    def sweep_label(self):
        """Where the run sits in its sweep: ``dt=0.001`` or ``tol=1e-09``."""
        return _settings_derived(self.settings)[0]

    @property  # (a report asks it of every run several times: 5e5 calls for 1e5 runs; the kept value read inline)
    def options_label(self):
        """Engine options as ``key=value`` words ("" for the defaults), values exactly as given: a run's identity."""
        s = self.settings
        return (s.__dict__.get(_DERIVED_KEY) or _settings_derived(s))[1]

    @property  # (asked of every run a hazard names, for what they share)
    def options_text(self):
        """``options_label`` as a report writes it: values by ``settings.option_text`` (4 significant digits)."""
        return _settings_derived(self.settings)[2]

    @_cached  # (a report asks it of every run in several sections)
    def cost_per_sim_s(self):
        """Median stepping wall time per simulated second of the horizon (s/s), NaN when not timed or with no
        horizon."""
        horizon = self.t_final if math.isfinite(self.t_final) and self.t_final > 0 else _NAN
        return self.cost.wall_s_median / horizon

    def max_error(self, quantity):
        """The max error over the horizon of ``quantity``, or NaN when not measured."""
        return self.errors.get(quantity, (_NAN, _NAN))[0]

    def with_trajectory(self, path):
        return replace(self, trajectory=path)

    # -------------------------------------------------------------- rows
    def to_row(self):
        """The flat, strict-JSON row (column names in the module docstring)."""
        row = {"key": self.key, "schema_version": self.schema_version, "case": self.case,
               "case_version": self.case_version, "params": json.dumps(self.params, sort_keys=True, default=list),
               "engine": self.engine, "engine_version": self.engine_version,
               "adapter_distribution": self.adapter_distribution, "adapter_version": self.adapter_version,
               "integrator": self.settings.integrator, "integrator_order": self.integrator_order,
               "dt": self.settings.dt, "rtol": self.settings.rtol, "atol": self.settings.atol,
               "options": json.dumps(dict(self.settings.options), sort_keys=True), "settings": self.settings_label,
               **{f"param_{k}": json.dumps(list(v)) if isinstance(v, (tuple, list)) else v
                  for k, v in self.params.items()},
               "status": self.status, "message": self.message, "t_final": self.t_final,
               "t_diverged": self.t_diverged, "traceback": self.traceback}
        row.update(asdict(self.cost), wall_s_repeats=json.dumps([_strict(w) for w in self.cost.wall_s_repeats]))
        for q, (mx, final) in self.errors.items():
            row[f"err_{q}_max"], row[f"err_{q}_final"] = mx, final
        row.update({f"drift_{n}": v for n, v in self.drifts.items()})
        row.update({f"drift_rate_{n}": v for n, v in self.drift_rates.items()})
        row.update({f"growth_{n}": v for n, v in self.growths.items()})
        row.update(self.checks)
        j = self.judgement
        row.update(within_tolerance=j.within_tolerance, beyond_tolerance=" ".join(j.beyond),
                   not_measured=" ".join(j.not_measured), verdict=j.verdict, verdict_reason=j.reason,
                   audit=json.dumps(self.audit, sort_keys=True, default=str), model=self.model,
                   provenance=json.dumps(self.provenance, sort_keys=True), trajectory=self.trajectory)
        return {k: _strict(v) for k, v in row.items()}

    @classmethod
    def from_row(cls, row):
        """Inverse of ``to_row``; reads ``READABLE_SCHEMAS``, raises ``SchemaError`` on others."""
        schema = row.get("schema_version", 1)
        if schema not in READABLE_SCHEMAS:
            raise SchemaError(f"row {row.get('key', '?')!r}: schema {schema!r}, this dalembert reads "
                              f"{list(READABLE_SCHEMAS)} — read it with the dalembert version that wrote it")
        errors, drifts, rates, growths = {}, {}, {}, {}
        for col, value in row.items():
            if col.startswith("err_") and col.endswith("_max"):
                q = col[len("err_"):-len("_max")]
                errors[q] = (_num(value), _num(row.get(f"err_{q}_final")))
            elif col.startswith("growth_"):
                growths[col[len("growth_"):]] = _num(value)
            elif col.startswith("drift_rate_"):
                rates[col[len("drift_rate_"):]] = _num(value)
            elif col.startswith("drift_"):
                drifts[col[len("drift_"):]] = _num(value)
        within = row.get("within_tolerance")
        return cls(
            key=row["key"], case=row["case"], case_version=row["case_version"], engine=row["engine"],
            settings=Settings(row["integrator"], _opt(row.get("dt")), _opt(row.get("rtol")), _opt(row.get("atol")),
                              json.loads(row.get("options") or "{}")),
            params={k: tuple(v) if isinstance(v, list) else v for k, v in json.loads(row.get("params") or "{}").items()},
            status=row["status"], message=row.get("message") or "", engine_version=row.get("engine_version") or "",
            adapter_distribution=_text(row.get("adapter_distribution")),
            adapter_version=_text(row.get("adapter_version")),
            integrator_order=None if _opt(row.get("integrator_order")) is None else int(row["integrator_order"]),
            t_final=_num(row.get("t_final")), t_diverged=_opt(row.get("t_diverged")),
            cost=Cost(**{f.name: _cost_field(f.name, row[f.name]) for f in fields(Cost) if f.name in row}),
            errors=errors, drifts=drifts, drift_rates=rates, growths=growths,
            checks={c: _num(row[c]) for c in CHECKS if row.get(c) is not None},
            judgement=Judgement(beyond=tuple((row.get("beyond_tolerance") or "").split()),
                                verdict=row.get("verdict") or "", reason=row.get("verdict_reason") or "",
                                within_tolerance=None if within is None or within != within else bool(within),
                                not_measured=tuple(_text(row.get("not_measured")).split())),
            audit=json.loads(row["audit"]) if isinstance(row.get("audit"), str) else {},
            model=row.get("model") if isinstance(row.get("model"), str) else "",
            provenance=json.loads(row["provenance"]) if isinstance(row.get("provenance"), str) else {},
            trajectory=row.get("trajectory") if isinstance(row.get("trajectory"), str) else "",
            traceback=row.get("traceback") if isinstance(row.get("traceback"), str) else "",
            schema_version=schema)


def _sweep_label(s):
    return f"dt={s.dt:g}" if s.dt is not None else f"tol={s.rtol:g}"


def _options_label(s):
    return " ".join(f"{k}={v}" for k, v in sorted(s.options.items()))


def _options_text(s):
    return " ".join(f"{k}={option_text(v)}" for k, v in sorted(s.options.items()))


# The values a record derives from its ``settings`` alone, each a function of the ``Settings``, in this order.
SETTINGS_DERIVED = {"sweep_label": _sweep_label, "options_label": _options_label, "options_text": _options_text}
_DERIVED_KEY = "_record_derived"  # (where a Settings keeps them: its own fields' names never start with "_")


def _settings_derived(s):
    """``SETTINGS_DERIVED``'s values of ``s``, made on the first read and kept in the frozen ``Settings``' own
    ``__dict__`` (as ``_cached`` keeps a record's: its fields, equality and hash are untouched): once per ``Settings``,
    not per record — records read together share theirs (``bulk_records``)."""
    got = s.__dict__.get(_DERIVED_KEY)
    if got is None:
        got = s.__dict__[_DERIVED_KEY] = tuple(make(s) for make in SETTINGS_DERIVED.values())
    return got


def _cost_field(name, value):
    """A stored ``Cost`` field back: counts as int, the repeats' JSON list as a tuple of floats."""
    if name in _COUNTS:
        if name == "batch_size" and (value is None or value != value):  # (absent, null or NaN: stepped alone)
            return 1
        return int(value or 0)
    if name in _TEXTS:
        return value if isinstance(value, str) else ""
    if name == "wall_s_repeats":
        return tuple(_num(w) for w in json.loads(value)) if isinstance(value, str) else ()
    return _num(value)


def _strict(v):
    """JSON-safe: numpy scalars to Python, non-finite floats to None."""
    if hasattr(v, "item") and not isinstance(v, (str, bytes)):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _text(v):
    """An optional stored text: "" when absent or null (pandas reads a missing column as NaN)."""
    return v if isinstance(v, str) else ""


def _num(v):
    """A stored number back as float (null and NaN read as NaN)."""
    return _NAN if v is None else float(v)


def _opt(v):
    """An optional stored number: None when absent or NaN (pandas reads None as NaN)."""
    return None if v is None or v != v else float(v)
