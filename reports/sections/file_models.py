"""What each engine's own reading of a robot's file changes (``reports.file_models``): per case, engine and
setting, the error of the scene-built run, of the file read with its effects off and with them on, and the
effects the engine read."""

from __future__ import annotations

import math

from dalembert.reports.file_models import file_readings
from dalembert.reports.page import Part
from dalembert.reports.tables import Cell, Table, num

__all__ = ["file_models"]

# The effects an engine's audit reports reading, in the order the table shows them.
EFFECTS = ("damping", "friction", "armature", "limits")
UNITS = {"joint": "rad", "orientation": "rad"}


def file_models(rep):
    """The file-reading section (a ``Part``; empty when no run read a file)."""
    part = Part()
    found = file_readings(rep.records)
    if not found:
        return part
    part.heading("What each engine's own reading of the file changes", 2, anchor="file-models")
    part.para("Every engine builds the case's scene, so all run one model; a run with --option model_file=PATH read "
              "the robot's file with the engine's own reader instead, with the file's damping, friction, armature and "
              "limits as the engine read them (effects on) or zeroed after the reading (effects off). The truth is "
              "the reference's on the scene: with the effects off a reading should move as the scene does (an error "
              "like the scene-built run's), with them on the gap is what the engine does with the file — a finding, "
              "not a failure of the engine.")
    changed = [f for f in found if math.isfinite(f.file_error) and f.file_error != f.scene_error]
    worst = max(changed, key=lambda f: abs(f.file_error - f.scene_error), default=None)
    if worst is None:
        part.para("No engine's reading of the file, with its effects on, changed the error of the scene-built run.")
    else:
        unit = UNITS.get(worst.quantity, "")
        part.para(f"Largest change: {worst.engine} on {worst.case} ({worst.file}, {worst.label}) ends "
                  f"{worst.file_error:.3g} {unit} from the truth with the file's effects on, against "
                  f"{worst.scene_error:.3g} {unit} built from the scene ({worst.quantity}).")
    head = ["case", "engine", "settings", "file", "quantity", "scene-built error", "file, effects off",
            "file, effects on", *[f"{e} (as read)" for e in EFFECTS], "cost scene (s/s)", "cost file (s/s)"]
    rows = [[Cell(f.case), Cell(f.engine), Cell(f.label, wrap=True), Cell(f.file, title=f.model_source),
             Cell(f.quantity), num(f.scene_error), num(f.bare_error), num(f.file_error),
             *[Cell(str(f.effects.get(e, "—")), wrap=True) for e in EFFECTS],
             num(f.scene_cost, "{:.3g}"), num(f.file_cost, "{:.3g}")] for f in found]
    part.table(Table(head, rows), collapsed=f"{len(found)} readings of a file beside their scene-built runs")
    return part
