"""Stability maps the hard suite runs by default: a case swept over one parameter, with every
fixed-step integrator's stability boundary searched in the step.

Declared beside the case they map (``stability_map(...)`` in its module, registered like
cases), and run by ``dalembert run --tag <a tag the map carries>`` (``--no-maps`` leaves them
out): the swept values, the step bracket and the fixed parameters (a horizon short enough for
tens of probes per curve) are the map's, the engines and integrators the selection's.
"""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.registry import Registry

__all__ = ["MapPlan", "MAPS", "stability_map"]

MAPS = Registry("stability map")


@dataclass(frozen=True)
class MapPlan:
    """One default stability map.

    Attributes
    ----------
    name : str
    case : str — the case mapped
    parameter : str — the swept parameter; values : str — its values, in ``--param`` syntax
        (``log:5,500,5``)
    bracket : (float, float) — the smallest and largest step searched, s
    params : dict — the case's other parameters for the map (horizon, sample interval)
    reason : str — why these values, this bracket and this horizon
    tags : tuple of str — the ``--tag`` selections that run it
    resolution : float — the search's resolution (``dalembert.harness.search``)
    """

    name: str
    case: str
    parameter: str
    values: str
    bracket: tuple
    params: dict
    reason: str
    tags: tuple = ("hard",)
    resolution: float = 1.5


def stability_map(name, **plan):
    """Register a ``MapPlan`` under ``name`` (the keyword arguments are its fields)."""
    return MAPS.register(name, MapPlan(name, **plan))
