"""How an engine is asked to integrate: ``Settings``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Settings", "SettingsError", "steps_per_interval", "knob_problems", "is_numerical_failure", "option_text",
           "OPTION_DIGITS"]

# An option's value in a label a reader reads (a report's legend, a finding): this many significant digits, as
# ``reports.formatting.value_text`` writes numbers; a ``log:`` grid's values (0.00447213595499958) print as 0.004472.
# Stored labels and values keep every digit.
OPTION_DIGITS = 4


def option_text(value):
    """An engine option's value (the text it was given) as a label a reader reads: a number that is not a whole
    one to ``OPTION_DIGITS`` significant digits, anything else (a name, a whole number) as given."""
    text = str(value)
    try:
        x = float(text)
    except ValueError:
        return text
    if not math.isfinite(x) or x == int(x) and "." not in text and "e" not in text.lower():
        return text  # a whole number as written (noslip_iterations=10), or inf/nan
    return f"{x:.{OPTION_DIGITS}g}"

# dt divides a sample interval when interval/dt is within this of an integer
# (sample times and dt are decimals, never exact in binary).
DIVIDES_REL_TOL = 1e-9
# Steps beyond 2^53 cannot even be counted exactly in double precision (nor by the int64
# step counters of the engines' loops): such a dt is refused, whatever the user asks.
MAX_COUNTABLE_STEPS = 2.0**53
# Below 100 unit roundoffs a relative tolerance asks more than double precision can deliver;
# scipy.integrate's solvers raise such an rtol to this themselves (with a warning).
RTOL_MIN = 100.0 * np.finfo(float).eps
# A relative tolerance of 1 or more lets each step err by as much as the state itself: it asks no
# accuracy at all, so an adaptive solver takes steps as long as its stability allows and a run "meets" it
# by construction. Refused, like a tolerance below RTOL_MIN.
RTOL_MAX = 1.0


class FrozenOptions(dict):
    """A read-only dict (picklable, unlike ``MappingProxyType``, so settings cross process boundaries)."""

    def _readonly(self, *args, **kwargs):
        raise TypeError("Settings.options is read-only; make new Settings instead")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = _readonly

    def __reduce__(self):
        return (FrozenOptions, (dict(self),))

    def __hash__(self):
        return hash(tuple(sorted(self.items())))


class SettingsError(ValueError):
    """Invalid integration settings; the message names the field and the fix."""


@dataclass(frozen=True)
class Settings:
    """Integration settings.

    Attributes
    ----------
    integrator : str
        Integrator name, lowercase and hyphenated (``rk4``, ``dop853``, ...).
    dt : float or None
        Fixed step (s), for fixed-step integrators; must divide the sample interval.
    rtol, atol : float or None
        Tolerances, for adaptive integrators.
    options : mapping
        Engine-specific options; an engine raises on names it does not know.
    """

    integrator: str
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None
    options: FrozenOptions = field(default_factory=FrozenOptions)

    def __post_init__(self):
        object.__setattr__(self, "options", FrozenOptions(self.options))
        problems = []
        if not isinstance(self.integrator, str) or not self.integrator:
            problems.append("integrator: give an integrator name, e.g. 'rk4'")
        for name in ("dt", "rtol", "atol"):
            v = getattr(self, name)
            if v is None:
                continue
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0.0:
                problems.append(f"{name}: must be a positive finite number, got {v!r}")
            else:
                object.__setattr__(self, name, float(v))
        if isinstance(self.rtol, float) and self.rtol >= RTOL_MAX:
            problems.append(f"rtol: {self.rtol!r} asks no accuracy (a relative error of {RTOL_MAX:g} or more is as "
                            "large as the state itself) — use rtol < 1, e.g. 1e-6")
        if problems:
            raise SettingsError("; ".join(problems))

    def label(self, brief=False):
        """THE label of these settings (stored as a run's ``settings`` column, written in the reports):
        ``rk4 dt=0.001`` or ``dop853 rtol=1e-09 atol=1e-09``, options appended as ``key=value``.

        ``brief``: the label a report writes: leave out an atol equal to the rtol (the default matrix's
        choice, which would double every adaptive label in a report's text), and write option values by
        ``option_text`` (0.004472, not 0.00447213595499958); the stored label keeps them as given.
        """
        parts = [self.integrator]
        for name in ("dt", "rtol", "atol"):
            v = getattr(self, name)
            if v is not None and not (brief and name == "atol" and v == self.rtol):
                parts.append(f"{name}={v:g}")
        parts += [f"{k}={option_text(v) if brief else v}" for k, v in sorted(self.options.items())]
        return " ".join(parts)


def steps_per_interval(times, dt):
    """Steps per sample interval, ndarray (n-1,) of int; ValueError if ``dt`` does not divide."""
    ratio = np.diff(times) / dt
    if np.sum(ratio) > MAX_COUNTABLE_STEPS:
        raise ValueError(f"dt: {dt!r} s would take {np.sum(ratio):.3g} steps over {times[-1] - times[0]:g} s, more "
                         f"than double precision can count ({MAX_COUNTABLE_STEPS:.3g}) — use a larger step")
    n = np.rint(ratio)
    bad = np.abs(ratio - n) > DIVIDES_REL_TOL * np.maximum(ratio, 1.0)
    if np.any(bad) or np.any(n < 1):
        k = int(np.argmax(bad | (n < 1)))
        raise ValueError(f"dt: {dt!r} does not divide the sample interval "
                         f"{float(times[k + 1] - times[k])!r} s — choose dt = interval / integer (or a "
                         "sample_interval that dt divides)")
    return n.astype(int)


def is_numerical_failure(exc):
    """True for the exceptions a blown-up state raises inside a stepping loop
    (overflow, a singular matrix, ``math`` functions of inf/NaN): a divergence,
    to be reported as NaN from that point on, not a crash."""
    import numpy.linalg

    return (isinstance(exc, (ArithmeticError, numpy.linalg.LinAlgError))
            or (isinstance(exc, ValueError) and "math domain error" in str(exc)))


def knob_problems(settings, who, fixed_step, options, times):
    """What is wrong with ``settings``' knobs for one integrator, as a list of messages.

    Parameters
    ----------
    who : str — the integrator as named in messages (e.g. ``'rk4'`` or ``mujoco 'rk4'``)
    fixed_step : bool — fixed-step (knob ``dt``) or adaptive (knobs ``rtol``, ``atol``)
    options : iterable of str — the option names it accepts
    times : array_like (n,) — the sample times a fixed step must divide (s)
    """
    problems = []
    unknown = sorted(set(settings.options) - set(options))
    if unknown:
        problems.append(f"options: {unknown} unknown to {who} (accepts {sorted(options) or 'none'})")
    if fixed_step:
        if settings.dt is None:
            problems.append(f"dt: {who} is fixed-step — give dt (s)")
        else:
            try:
                steps_per_interval(np.asarray(times, dtype=float), settings.dt)
            except ValueError as e:
                problems.append(str(e))
        if settings.rtol is not None or settings.atol is not None:
            problems.append(f"rtol/atol: {who} is fixed-step — give dt, not tolerances")
    elif settings.dt is not None:
        problems.append(f"dt: {who} is adaptive — give rtol/atol, not dt")
    elif settings.rtol is not None and settings.rtol < RTOL_MIN:
        problems.append(f"rtol: {settings.rtol!r} is below what double precision resolves ({RTOL_MIN:.2g}, 100 unit "
                        f"roundoffs) — use rtol >= {RTOL_MIN:.2g}")
    return problems

