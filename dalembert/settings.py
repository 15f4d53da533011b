"""How an engine is asked to integrate: ``Settings``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["Settings", "SettingsError"]


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
        if problems:
            raise SettingsError("; ".join(problems))

    def label(self):
        """Short human label, e.g. ``rk4 dt=0.001`` or ``dop853 rtol=1e-10``."""
        parts = [self.integrator]
        for name in ("dt", "rtol", "atol"):
            v = getattr(self, name)
            if v is not None:
                parts.append(f"{name}={v:g}")
        parts += [f"{k}={v}" for k, v in sorted(self.options.items())]
        return " ".join(parts)
