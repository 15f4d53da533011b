"""What each engine's own reading of a robot's file changes: its runs with ``model_file`` beside its scene-built ones.

An engine run with ``--option model_file=PATH`` read the robot's file with its own reader (MuJoCo's compiler,
Pinocchio's or Drake's URDF reader) instead of building the scene, with the file's effects as it read them
(``file_effects=on``) or zeroed (``off``). Here each such run is paired with the same engine's scene-built run at
the same integrator, step (or tolerance) and other options, in the same case version: the errors against the
truth (the reference's, on the scene) side by side, and the effects the engine's audit says it read. With the
effects off the reading should move as the scene does; with them on, the gap is what the engine does with the
file, a finding rather than a failure.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from dalembert.reports.work_precision import cost_per_sim_s

__all__ = ["FileReading", "file_readings", "FILE_OPTIONS", "SCENE"]

# The options that choose the model's source (``dalembert.adapters.file_model``): every other option pairs runs.
FILE_OPTIONS = ("model_file", "file_effects")
SCENE = "scene"


@dataclass(frozen=True)
class FileReading:
    """One engine's reading of one file at one setting, beside its scene-built run.

    Attributes
    ----------
    case : str — case name (its version in ``case_version``)
    case_version : str
    engine : str
    label : str — integrator, step or tolerance, other options
    file : str — the file's name
    quantity : str — the error quantity compared (``joint``, else ``orientation``)
    scene_error, bare_error, file_error : float — max error against the truth of the scene-built run, the file read
        with its effects off, and with them on (NaN where not run or not finished)
    scene_cost, file_cost : float — stepping s per simulated s of the scene-built run and the file-read one (on)
    effects : dict — what the engine read of the file's effects (its audit's ``file_effects_read``), by effect
    model_source : str — how the engine read the file (its audit's)
    """

    case: str
    case_version: str
    engine: str
    label: str
    file: str
    quantity: str
    scene_error: float
    bare_error: float
    file_error: float
    scene_cost: float
    file_cost: float
    effects: dict
    model_source: str


def _source(r):
    """``(file or None, effects on)`` of a run: None where its engine built the scene."""
    options = dict(r.settings.options)
    path = options.get("model_file", SCENE)
    return (None if path == SCENE else path), options.get("file_effects", "on") == "on"


def _pair_key(r):
    options = tuple(sorted((k, v) for k, v in r.settings.options.items() if k not in FILE_OPTIONS))
    return r.case, r.case_version, r.engine, r.settings.integrator, r.settings.dt, r.settings.rtol, options


def _label(r):
    step = f"dt={r.settings.dt:g}" if r.settings.dt is not None else f"rtol={r.settings.rtol:g}"
    others = " ".join(f"{k}={v}" for k, v in sorted(r.settings.options.items()) if k not in FILE_OPTIONS)
    return " ".join(x for x in (r.settings.integrator, step, others) if x)


def _error(r, quantity):
    return r.max_error(quantity) if r is not None and r.status == "ok" else math.nan


def file_readings(records):
    """Every ``FileReading`` in ``records`` (RunRecords), by case, engine and label; [] where no run read a file."""
    if not any(r.settings.options.get("model_file", SCENE) != SCENE for r in records):
        return []  # (no run read a file: nothing to pair, asked of every run of a map otherwise)
    groups = {}
    for r in records:
        path, on = _source(r)
        if path is None and not on:  # file_effects=off without a file: refused, nothing to pair
            continue
        groups.setdefault(_pair_key(r), {})[(path, on)] = r
    out = []
    for key, runs in groups.items():
        for path in sorted({p for p, _ in runs if p is not None}):
            scene, bare, read = runs.get((None, True)), runs.get((path, False)), runs.get((path, True))
            present = [r for r in (scene, bare, read) if r is not None]
            quantity = next((q for q in ("joint", "orientation") if any(not math.isnan(r.max_error(q))
                                                                         for r in present)), "joint")
            audit = next((r.audit for r in (read, bare) if r is not None and r.audit), {})
            out.append(FileReading(key[0], key[1], key[2], _label(present[0]), os.path.basename(path), quantity,
                                   _error(scene, quantity), _error(bare, quantity), _error(read, quantity),
                                   cost_per_sim_s(scene) if scene is not None else math.nan,
                                   cost_per_sim_s(read) if read is not None else math.nan,
                                   dict(audit.get("file_effects_read", {})), audit.get("model_source", "")))
    return sorted(out, key=lambda f: (f.case, f.engine, f.label, f.file))
