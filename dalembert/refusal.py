"""What an engine refuses to run, known before a matrix runs: a ``Refusal``, listed once, never a run.

An engine declares what it cannot represent (``Adapter.unsupported_before_build``: its effects, options and
the scene's parts; no model built). The matrix asks before anything runs and leaves those runs out: each
engine's refusals of one case variant for one reason are one ``Refusal`` (the integrators and option sets
refused there, and how many runs that is), written in the matrix's manifest (``"refused"``, ``to_json``) so
that a report lists them without importing any engine. A refusal only the built model shows (MJX's
``put_model``) stays a run stored ``unsupported``, as every refusal was before; a report words both alike
(``settings_text``).
"""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.settings import option_text

__all__ = ["Refusal", "group", "settings_text", "manifest_refusals"]


@dataclass(frozen=True)
class Refusal:
    """One engine's refusal of one case variant, for one reason.

    Attributes
    ----------
    engine, case : str
    params : tuple of (str, value) — the case parameters given, sorted by name (a vector as a tuple)
    case_version : str — the case's content hash (``Case.version``) the matrix was made for
    reason : str — the engine's words (``Adapter.unsupported``'s text)
    settings : tuple of (str, tuple of (str, str)) — each refused integrator with its engine options (sorted
        (key, value) pairs; ``()``: the defaults), in the matrix's order, each once
    runs : int — the matrix's runs it stands for (every step or tolerance of those settings)
    """

    engine: str
    case: str
    params: tuple
    case_version: str
    reason: str
    settings: tuple
    runs: int

    @property
    def integrators(self):
        """The refused integrators, sorted, each once."""
        return sorted({integrator for integrator, _ in self.settings})

    @property
    def what(self):
        """The refused settings as a report words them (``settings_text``): ``"euler and rk4 with node=ep"``."""
        return settings_text([(i, " ".join(f"{k}={option_text(v)}" for k, v in o)) for i, o in self.settings])

    def text(self):
        """One line: ``"exudyn cannot run four_bar with rk44 and rk4: <reason>"`` (parameters given in brackets)."""
        given = ", ".join(f"{k}={_value(v)}" for k, v in self.params)
        case = self.case + (f" ({given})" if given else "")
        return f"{self.engine} cannot run {case} with {self.what}: {self.reason}"

    def to_json(self):
        return {"engine": self.engine, "case": self.case,
                "params": [[k, list(v) if isinstance(v, tuple) else v] for k, v in self.params],
                "case_version": self.case_version, "reason": self.reason,
                "settings": [{"integrator": i, "options": [list(p) for p in o]} for i, o in self.settings],
                "runs": self.runs}

    @classmethod
    def from_json(cls, d):
        """Inverse of ``to_json``; KeyError or TypeError when ``d`` is not a refusal's JSON."""
        params = tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in d["params"])
        settings = tuple((s["integrator"], tuple(tuple(p) for p in s["options"])) for s in d["settings"])
        return cls(d["engine"], d["case"], params, d["case_version"], d["reason"], settings, int(d["runs"]))


def group(refused):
    """The ``Refusal``s of ``refused``: ``[(spec, reason)]`` (a ``RunSpec``: ``engine``, ``case``, ``params``,
    ``case_version``, ``settings``), one per engine, case variant and reason, in the order first met."""
    groups = {}
    for spec, reason in refused:
        key = (spec.engine, spec.case, spec.params, spec.case_version, reason)
        settings, runs = groups.get(key, ({}, 0))
        settings[(spec.settings.integrator, tuple(sorted(spec.settings.options.items())))] = None
        groups[key] = (settings, runs + 1)
    return tuple(Refusal(*key, tuple(settings), runs) for key, (settings, runs) in groups.items())


def settings_text(refused):
    """What an engine refuses, as a report writes it: ``refused`` is ``[(integrator, options text)]`` (options as
    ``RunRecord.options_text`` words them, ``""`` for the defaults). The integrators (``"euler and rk4"``), with
    the options where all share them (``"euler and rk4 with node=ep"``), else each integrator with its own."""
    options = {o for _, o in refused}
    if len(options) > 1:
        return _list(sorted({" ".join(x for x in pair if x) for pair in refused}))
    what = _list(sorted({i for i, _ in refused}))
    return what + (f" with {next(iter(options))}" if options and next(iter(options)) else "")


def manifest_refusals(manifest):
    """The ``Refusal``s a matrix's manifest lists (``()`` for a store written before refusals were listed: its
    refused runs are rows); ValueError naming the field when the list is not one dalembert wrote."""
    listed = (manifest or {}).get("refused") or []
    try:
        return tuple(Refusal.from_json(d) for d in listed)
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise ValueError(f"manifest.refused: not the refusals dalembert writes ({type(e).__name__}: {e}) — the "
                         "manifest was edited or damaged; write the store again with dalembert run") from None


def _value(v):
    return ",".join(f"{x:g}" if isinstance(x, float) else str(x) for x in v) if isinstance(v, tuple) else str(v)


def _list(items):
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]
