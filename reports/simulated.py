"""What each engine simulated beyond the scene, side by side: the few things its effects audit (``RunRecord.audit``,
read back from the engine by its adapter) says that the scene does not — number type, gravity as the engine stores
it, how loop closures are held (softness, regularisation, stabilisation gains), where it ran, a known issue.

Audits differ in keys per engine; ``ASPECTS`` names, per aspect, the audit keys that carry it (the first found
wins, a nested key as ``outer.inner``), so one table compares them. Stored values only, as the audits wrote them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dalembert.reports.formatting import value_text

__all__ = ["ASPECTS", "TEXT_CHARS", "Aspect", "Simulated", "simulated"]


@dataclass(frozen=True)
class Aspect:
    """One column: its header and the audit keys that carry it, in order of preference (``every``: each key found,
    named by its last part — gains come in several keys — else the first found alone)."""

    name: str
    keys: tuple
    every: bool = False
    scene: bool = False  # the value is the scene's gravity as the engine stores it: shown only where it differs


# What the table compares (the keys as the adapters' audits write them: ``adapters/*/audit.py``).
ASPECTS = (
    Aspect("number type", ("precision", "dtype_qpos")),
    Aspect("gravity as stored (m/s²)", ("gravity_device", "gravity"), scene=True),
    Aspect("loop constraints", ("loop_softness", "loop_stiffness", "drift_correction.method", "loop_solver",
                                "loops.closures", "loop_constraints")),
    Aspect("regularisation", ("proximal.mu", "loop_solimp", "loop_parameters.constraint_force_mixing"), every=True),
    Aspect("stabilisation gains", ("drift_correction.Kp", "drift_correction.Kd", "loop_solref",
                                   "loop_parameters.error_reduction_parameter"), every=True),
    Aspect("where it ran", ("backend",)),
    Aspect("known issue", ("known_issue",)),
)
# A long audit string is cut to this many characters in a cell (whole on hover and in the raw audit).
TEXT_CHARS = 110


@dataclass(frozen=True)
class Simulated:
    """One engine's row: ``values`` per aspect name, ``(short text, full text)`` ("" where its audits say
    nothing), and ``run`` the run whose raw audit the row links to (a loop case's, where it has one)."""

    engine: str
    values: dict
    run: object


def _get(audit, key):
    node = audit
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def _zero(value):
    return isinstance(value, (list, tuple)) and bool(value) and all(isinstance(v, (int, float)) and v == 0
                                                                    for v in value)


def _text(value):
    if isinstance(value, dict):
        return ", ".join(f"{k}: {_text(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(repr(v) if isinstance(v, float) else _text(v) for v in value) + "]"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    return value_text(value)


def _aspect(audits, aspect):
    """The aspect's text over ``audits`` (``[(options text, audit, scene gravity)]``); distinct values with the
    options they came with ("defaults" for none); a ``scene`` aspect equal to the scene's everywhere is "as the
    scene", else its values where it differs, beside the scene's."""
    seen = {}
    differs = False
    for options, audit, gravity in audits:
        if aspect.scene:
            value = next((v for v in (_get(audit, k) for k in aspect.keys) if v is not None), None)
            if value is None or _zero(value) or [float(x) for x in value] == [float(x) for x in gravity]:
                continue
            differs = True
            text = f"{_text(value)}, the scene {_text([float(x) for x in gravity])}"
            seen.setdefault(text, []).append(options)
            continue
        # (a zero vector is the scene's, not the engine's: a case without gravity)
        found = [(k, v) for k, v in ((k, _get(audit, k)) for k in aspect.keys) if v is not None and not _zero(v)]
        if not found:
            continue
        text = ("; ".join(f"{k.split('.')[-1]} {_text(v)}" for k, v in found) if aspect.every
                else _text(found[0][1]))
        seen.setdefault(text, []).append(options)
    if aspect.scene and not differs:
        return "as the scene" if any(_get(a, k) is not None for _, a, _ in audits for k in aspect.keys) else ""
    if len(seen) <= 1:
        return next(iter(seen), "")
    return " | ".join(f"{t} ({', '.join(sorted(set(o for o in opts if o))) or 'defaults'})" for t, opts in seen.items())


def simulated(records, scene_gravity):
    """A ``Simulated`` per engine of ``records`` (by name) whose finished runs stored an audit; ``scene_gravity``:
    a run's scene's gravity (m/s², world; ``Scene.gravity``)."""
    by_engine = {}
    for r in records:
        if r.ok and r.audit:
            by_engine.setdefault(r.engine, []).append(r)
    out = []
    for engine, runs in sorted(by_engine.items()):
        # one audit per case and options (the audits of one case's steps differ in the step alone)
        kept = {}
        for r in runs:
            kept.setdefault((r.case, r.options_label), r)
        audits = [(r.options_text, r.audit, scene_gravity(r)) for r in kept.values()]
        values = {}
        for aspect in ASPECTS:
            full = _aspect(audits, aspect)
            values[aspect.name] = (full if len(full) <= TEXT_CHARS else full[:TEXT_CHARS - 1] + "…", full)
        loop_run = next((r for r in kept.values() if any(_get(r.audit, k) is not None for k in ASPECTS[2].keys)),
                        next(iter(kept.values())))
        out.append(Simulated(engine, values, loop_run))
    return out
