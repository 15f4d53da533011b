"""A case's parameters: the domain each one must lie in, checked whenever a case is made.

A case factory declares its parameters' domains once, in ``@case`` (``dalembert.case``):
``positive`` (lengths, masses, radii, inertias, gravity's magnitude, sample intervals: finite and
> 0, every component of a vector one) and ``counts`` (numbers of links, bodies: whole numbers
>= 1). Every numeric parameter, declared or not, must be a finite real number of at most
``MAX_MAGNITUDE`` (every component of a vector one), and ``t_final`` is always positive: a case
runs without arguments, and every factory has it (``dalembert.case.case``). The checks run
before the factory, so a zero-length rod is refused with its parameter's name instead of running
"ok" with every error exactly 0. ``parse_param`` reads ``--param KEY=VALUE``, typed after the default.
"""

from __future__ import annotations

import numbers

from dalembert.registry import suggest

__all__ = ["MAX_MAGNITUDE", "MIN_POSITIVE", "ALWAYS_POSITIVE", "domain_problems", "parse_param"]

# Every quantity a case derives from its parameters (an inertia m l^2 / 12, an energy I w^2 / 2, a
# period 2 pi sqrt(l / g)) is a product of powers of a few of them, at most six factors: with every
# parameter's magnitude at most 1e50 such a product stays below 1e300, under the largest double
# (1.8e308) ...
MAX_MAGNITUDE = 1e50
# ... and with every positive one at least 1e-50 it stays above 1e-300, over the smallest normal
# double (2.2e-308): a rod of length 1e-300 would have an inertia that underflows to zero.
MIN_POSITIVE = 1e-50
# The horizon (s) is a parameter of every case (``@case`` requires it) and is always a duration.
ALWAYS_POSITIVE = ("t_final",)


def _is_real(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _is_count(v):
    return isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= 1


def domain_problems(case_name, defaults, values, positive=(), counts=(), units=None):
    """What is wrong with a case's parameter ``values``, one message per parameter.

    Parameters
    ----------
    case_name : str — names each problem, ``<case_name>.<parameter>: ...``
    defaults : dict name -> default — the factory's signature; a parameter is numeric when its
        default is (a float, an int or a tuple of them), and a vector must keep its length
    values : dict name -> value — the parameters to check (names of ``defaults`` only)
    positive : iterable of str — must be > 0 (at least ``MIN_POSITIVE``), every component of a vector
    counts : iterable of str — must be whole numbers >= 1
    units : dict name -> str — each parameter's unit, quoted in the messages

    Returns
    -------
    list of str — "case.param: what is wrong — the fix"; empty when every value lies in its domain
    """
    units = units or {}
    positive = set(positive) | set(ALWAYS_POSITIVE)
    problems = []
    for key, value in values.items():
        default = defaults[key]
        where = f"{case_name}.{key}"
        unit = f" ({units[key]})" if key in units else ""
        if key in counts:
            if not _is_count(value):
                problems.append(f"{where}: must be a whole number >= 1{unit}, got {value!r} — give a count, "
                                f"e.g. {default!r}")
            continue
        if isinstance(default, bool):
            if not isinstance(value, bool):
                problems.append(f"{where}: must be True or False, got {value!r} — give one of them")
            continue
        if isinstance(default, tuple):
            if not isinstance(value, (tuple, list)) or len(value) != len(default):
                problems.append(f"{where}: expected {len(default)} numbers like {default!r}, got {value!r} — give "
                                f"all {len(default)}{unit} (comma-separated after --param)")
                continue
            components, every, some = tuple(value), " in every component", " (a component)"
        elif _is_real(default):
            components, every, some = (value,), "", ""
        else:
            continue  # a string or another kind of parameter: the factory checks its own
        if not all(_is_real(v) for v in components):
            problems.append(f"{where}: must be {'numbers' if every else 'a number'}{unit}, got {value!r} — give "
                            f"e.g. {default!r}")
        elif not all(v == v and abs(v) != float("inf") for v in components):
            problems.append(f"{where}: must be finite{unit}, got {value!r} — give a finite value, e.g. {default!r}")
        elif any(abs(v) > MAX_MAGNITUDE for v in components):
            problems.append(f"{where}: {value!r}{unit} is beyond {MAX_MAGNITUDE:g} in magnitude{some}, where the "
                            "case's derived quantities (inertias, energies: products of its parameters) overflow "
                            f"a double — give a value within {MAX_MAGNITUDE:g} (or change its unit)")
        elif key in positive and not all(v > 0.0 for v in components):
            problems.append(f"{where}: must be positive{unit}{every}, got {value!r} — a zero or negative {key} has "
                            "no physical meaning: give a value > 0")
        elif key in positive and any(v < MIN_POSITIVE for v in components):
            problems.append(f"{where}: {value!r}{unit} is below {MIN_POSITIVE:g}{some}, where the case's derived "
                            "quantities (inertias, energies: products of its parameters) underflow to zero — give "
                            f"a value of at least {MIN_POSITIVE:g} (or change its unit)")
    return problems


def parse_param(factory, text):
    """Parse ``KEY=VALUE`` for ``factory``, typed after the parameter's default.

    Vectors are comma-separated numbers (``omega0=0,1,1``).
    """
    if "=" not in text:
        raise ValueError(f"--param {text!r}: write KEY=VALUE")
    key, value = text.split("=", 1)
    defaults = factory.params
    if key not in defaults:
        raise ValueError(f"--param {key!r}: case {factory.name!r} has no such parameter{suggest(key, defaults)}")
    default = defaults[key]
    try:
        if isinstance(default, bool):
            if value.lower() not in ("true", "false", "1", "0"):
                raise ValueError
            return key, value.lower() in ("true", "1")
        if isinstance(default, int):
            return key, int(value)
        if isinstance(default, float):
            return key, float(value)
        if isinstance(default, tuple):
            return key, tuple(float(v) for v in value.split(","))
        return key, value
    except ValueError:
        raise ValueError(f"--param {key}={value!r}: expected {type(default).__name__} "
                         f"like {default!r}") from None
