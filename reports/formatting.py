"""How the report and its findings print a time or a parameter: at a reader's precision.

A time computed as a sum of steps carries float noise (``0.35000000000000003``); a
parameter given as ``0.3`` may be stored as ``0.30000000000000004``. ``value_text`` prints
either with ``SIGNIFICANT`` digits and no trailing zeros (``0.35``, ``1e-05``, ``20``), the
one format every time and parameter in the report goes through; the stored values keep
their full precision (``summary.csv``, ``dalembert export``).
"""

from __future__ import annotations

import numbers

__all__ = ["SIGNIFICANT", "value_text", "params_text", "counted"]

# Digits a time or a parameter prints with: float noise sits at the 16th-17th digit, and a
# sweep's values differ in the first few (0.1 s steps, spins 1..10 rad/s).
SIGNIFICANT = 4


def value_text(x, unit=""):
    """``x`` as text: a real number to ``SIGNIFICANT`` significant digits (``%.4g``), an integer
    whole, anything else (a name, a bool, a list) as ``str`` gives it; `` unit`` appended when given.

    >>> value_text(0.35000000000000003, "s")
    '0.35 s'
    """
    if isinstance(x, numbers.Integral) and not isinstance(x, bool):
        text = str(int(x))
    elif isinstance(x, numbers.Real) and not isinstance(x, bool):
        text = f"{float(x):.{SIGNIFICANT}g}"
    elif isinstance(x, (list, tuple)):
        text = "[" + ", ".join(value_text(v) for v in x) + "]"
    else:
        text = str(x)
    return f"{text} {unit}" if unit else text


def params_text(params):
    """A case's parameters as ``name=value, ...`` (sorted by name, values by ``value_text``); "" for none."""
    return ", ".join(f"{k}={value_text(v)}" for k, v in sorted(params.items()))


def counted(n, word, many=None):
    """``n`` and ``word`` in the number it takes: ``counted(1, "run")`` is "1 run", ``counted(2, "run")`` "2 runs"
    (``many``: the plural where it is not ``word + "s"``)."""
    return f"{n} {word if n == 1 else (many or word + 's')}"
