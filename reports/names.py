"""How the report names a run and writes a speed: one spelling for every section and finding."""

from __future__ import annotations

__all__ = ["settings_text", "run_name", "speed_text", "SPEED_UNITS"]

def settings_text(r):
    """A run's settings as the report writes them: ``Settings.label(brief=True)`` (no atol equal
    to the rtol, the default matrix's choice, which would double every adaptive label)."""
    return r.settings.label(brief=True)


# A speed's unit in a sentence: the largest of these (m/s) at or below it, so a creep reads "1.8 mm/s", not
# "0.0018 m/s"; speeds below the last are written in it.
SPEED_UNITS = ((1.0, "m/s"), (1e-3, "mm/s"), (1e-6, "um/s"), (1e-9, "nm/s"))


def speed_text(v):
    """A speed ``v`` (m/s) as text in the unit that reads best (``SPEED_UNITS``): ``speed_text(0.0018)`` is
    "1.8 mm/s"."""
    scale, unit = next(((s, u) for s, u in SPEED_UNITS if abs(v) >= s), SPEED_UNITS[-1])
    return f"{v / scale:.3g} {unit}"


def run_name(r):
    """How a finding names a run: ``engine integrator dt=... options``."""
    return f"{r.engine} {settings_text(r)}"


