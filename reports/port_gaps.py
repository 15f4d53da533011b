"""A port's systematic gaps from its original (MJX and MuJoCo Warp against MuJoCo C), from stored runs only.

``reports.parity`` measures each port run against its original's at the same settings; most differences
there are roundoff, a few are a chaotic case amplifying it. What the port computes differently, on every
case where it shows, is one of three gaps, each decided from the store:

* *number type* — on the settings where the port's float64 run agrees with the original to within
  ``AGREE_ROUNDOFF`` (the same computation) and stays near the truth (orientation error below
  ``reports.order.SATURATED_ANGLE``), its float32 run's difference from the original is the float32 roundoff
  alone: the floor the port's default number type puts under every error (``NumberFloor``);
* *order* — a port's integrator whose step pairs in the asymptotic range (``reports.order.step_pairs``) show an
  order below the original's on the same case, integrator and steps by more than ``reports.order.ORDER_MARGIN``
  (``OrderGap``). The original's order over the same two steps is taken from its raw errors, the roundoff floor
  not applied: roundoff only flattens a slope, so that order is a lower bound on the original's;
* *the same numbers as another integrator* — the port's integrator X gives integrator Y's headline error to
  ``SAME_RESULT`` (it computes Y) at a case and step where the original's X and Y differ (``SameAs``): MJX's
  implicitfast on a free body.

Each gap names the cases it shows on and their joints (a free body's six speeds are a free joint here), and
quotes the stored errors it comes from.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass

from dalembert.reports.causes import single_precision
from dalembert.reports.order import ORDER_MARGIN, SATURATED_ANGLE, step_pairs
from dalembert.reports.parity import PORT_ONLY_OPTIONS, PORTS

__all__ = ["AGREE_ROUNDOFF", "SAME_RESULT", "NumberFloor", "OrderGap", "SameAs", "number_floors", "order_gaps",
           "same_as", "joint_kinds"]

# A float64 port run within 1e-9 rad of its original is the same computation: double precision's epsilon,
# 2.2e-16, accumulated even linearly over the 1e2 to 1e5 steps of a horizon stays below 1e-10, and 1e-9 is
# three decades under float32's floor (``reports.order.SINGLE_FLOOR``, 1e-6), so the float32 twin's
# difference beside it is the number type's alone. A chaotic case, whose float64 runs already part by
# more (free_top_intermediate: 1.8e-8 rad), is left out.
AGREE_ROUNDOFF = 1e-9
# Two runs whose headline errors agree to 1e-6 relative are one computation: two methods of different
# update differ at first order in the step (1e-3 relative and more at the matrix's steps), and float32's
# roundoff on one computation is bit for bit the same from run to run.
SAME_RESULT = 1e-6


@dataclass(frozen=True)
class NumberFloor:
    """The float32 floor of a port: the range of its float32 runs' differences from the original (rad).

    Attributes
    ----------
    port, original : str — engine names
    low, high : float — the least and the largest orientation difference, rad
    settings : int — how many settings gave one (each with its float64 twin within ``AGREE_ROUNDOFF`` of the
        original and within ``SATURATED_ANGLE`` of the truth)
    cases : tuple of str
    """

    port: str
    original: str
    low: float
    high: float
    settings: int
    cases: tuple


@dataclass(frozen=True)
class OrderGap:
    """A port's integrator that converges at a lower order than its original's on some cases.

    Attributes
    ----------
    port, original, integrator : str
    options : str — the port's options (``key=value`` words)
    quantity : str — the headline error
    cases : tuple of str — the cases it shows on
    port_order, original_order : float — the medians of the pairs' orders (the original's: a lower bound)
    example : tuple — (case, (dt1, dt2) s, (port e1, e2), (original e1, e2)) of the first pair, the quantity's unit
    kept : tuple of str — the cases where the port's pairs keep the original's order (any headline quantity)
    """

    port: str
    original: str
    integrator: str
    options: str
    quantity: str
    cases: tuple
    port_order: float
    original_order: float
    example: tuple
    kept: tuple = ()


@dataclass(frozen=True)
class SameAs:
    """A port's integrator that computes another of its integrators where the original's two differ.

    Attributes
    ----------
    port, original, integrator, like : str — the port's ``integrator`` gives ``like``'s numbers
    cases : tuple of str
    example : tuple — (case, dt s, quantity, the port's error, the original's error with ``integrator``): the
        setting where the two differ most
    """

    port: str
    original: str
    integrator: str
    like: str
    cases: tuple
    example: tuple


def _plain_options(r):
    """Run ``r``'s options less the ones only its port has (MJX's precision), as sorted pairs."""
    return tuple(sorted((k, v) for k, v in r.settings.options.items() if k not in PORT_ONLY_OPTIONS.get(r.engine, ())))


def _params(r):
    return tuple(sorted((k, str(v)) for k, v in r.params.items()))


def number_floors(parities, records):
    """Per port, its ``NumberFloor``: a list, empty where no port ran float32 beside an agreeing float64 twin.

    Parameters
    ----------
    parities : sequence of reports.parity.Parity
    records : dict — run key -> RunRecord (the port runs' settings)
    """
    twins = {}
    for p in parities:
        r = records[p.port_key]
        twins.setdefault((p.port, p.case, p.version, r.settings.integrator, r.settings.dt, r.settings.rtol,
                          _plain_options(r), _params(r)), {})[p.number_type] = p
    per_port = {}
    for (port, case, *_), pair in sorted(twins.items(), key=lambda kv: str(kv[0])):
        single, double = pair.get("float32"), pair.get("float64")
        if single is None or double is None or not double.orientation <= AGREE_ROUNDOFF:
            continue
        # a motion already far from the truth (an angle error past SATURATED_ANGLE: the heavy top at Euler's coarse
        # steps) amplifies roundoff at every step: its float32 difference is no floor
        if not records[double.port_key].max_error("orientation") < SATURATED_ANGLE:
            continue
        if math.isfinite(single.orientation):
            per_port.setdefault(port, []).append((case, single.orientation))
    return [NumberFloor(port, PORTS[port], min(d for _, d in got), max(d for _, d in got), len(got),
                        tuple(sorted({c for c, _ in got}))) for port, got in sorted(per_port.items())]


def order_gaps(found_cases):
    """The ``OrderGap``s of every port in ``found_cases`` (``reports.findings.CaseFindings``: ``case``, ``runs``,
    ``quantity``), sorted by port, integrator and options."""
    groups, kept = {}, {}
    for f in found_cases:
        if f.quantity is None or f.case.scene.contacts:
            continue
        originals = {}
        for r in f.runs:
            if r.engine in PORTS.values() and r.ok and r.settings.dt is not None:
                originals[(r.engine, r.settings.integrator, _plain_options(r), _params(r), r.settings.dt)] = r
        ports = [r for r in f.runs if r.engine in PORTS]
        for p in step_pairs([(f.case, ports, f.quantity)]):
            coarse = next(r for r in ports if r.key == p.keys[0])
            head = (PORTS[p.engine], p.integrator, _plain_options(coarse), _params(coarse))
            a, b = originals.get(head + (p.dts[0],)), originals.get(head + (p.dts[1],))
            if a is None or b is None:
                continue
            e1, e2 = a.max_error(f.quantity), b.max_error(f.quantity)
            if not (e1 > 0 and e2 > 0 and math.isfinite(e1) and math.isfinite(e2)):
                continue
            theirs = math.log(e1 / e2) / math.log(p.dts[0] / p.dts[1])
            # a gap: a lower order, and behind the original at both steps (a port ahead at the coarse step, where
            # the original's own error is something else, a soft constraint's, is no gap in the method)
            if theirs - p.order > ORDER_MARGIN and p.errors[0] > e1 and p.errors[1] > e2:
                groups.setdefault((p.engine, p.integrator, p.options, f.quantity), []).append(
                    (f.case.name, p, theirs, (e1, e2)))
            else:
                kept.setdefault((p.engine, p.integrator, p.options), set()).add(f.case.name)
    out = []
    for (port, integrator, options, quantity), got in sorted(groups.items()):
        case, p, _, theirs = got[0]
        cases = tuple(sorted({c for c, *_ in got}))
        out.append(OrderGap(port, PORTS[port], integrator, options, quantity, cases,
                            statistics.median(g[1].order for g in got), statistics.median(g[2] for g in got),
                            (case, p.dts, p.errors, theirs),
                            tuple(sorted(kept.get((port, integrator, options), set()) - set(cases)))))
    return out


def _same(a, b):
    return math.isfinite(a) and math.isfinite(b) and abs(a - b) <= SAME_RESULT * max(abs(a), abs(b))


def same_as(found_cases):
    """The ``SameAs`` gaps of every port in ``found_cases`` (``CaseFindings``), sorted by port and integrators."""
    groups = {}
    for f in found_cases:
        if f.quantity is None:
            continue
        runs = {}
        for r in f.runs:
            if r.ok and r.settings.dt is not None:
                plain = _plain_options(r) if r.engine in PORTS else tuple(sorted(r.settings.options.items()))
                runs[(r.engine, single_precision(r), plain, _params(r), r.settings.dt, r.settings.integrator)] = r
        for (engine, single, plain, params, dt, x), rx in sorted(runs.items(), key=lambda kv: str(kv[0])):
            if engine not in PORTS or single:  # (float32 runs: the number type's gap, ``number_floors``)
                continue
            original = PORTS[engine]
            for (e2, s2, p2, q2, d2, y), ry in runs.items():
                if (e2, s2, p2, q2, d2) != (engine, single, plain, params, dt) or y == x:
                    continue
                if not _same(rx.max_error(f.quantity), ry.max_error(f.quantity)):
                    continue
                ox = runs.get((original, False, plain, params, dt, x))
                oy = runs.get((original, False, plain, params, dt, y))
                # the original's X and Y differ, and the port's X is not the original's X (the port's Y is)
                if (ox is None or oy is None or _same(ox.max_error(f.quantity), oy.max_error(f.quantity))
                        or _same(rx.max_error(f.quantity), ox.max_error(f.quantity))):
                    continue
                groups.setdefault((engine, x, y), []).append(
                    (f.case.name, dt, f.quantity, rx.max_error(f.quantity), ox.max_error(f.quantity)))
    out = []
    for (port, x, y), got in sorted(groups.items()):
        example = max(got, key=lambda g: g[3] / g[4] if g[4] > 0 else math.inf)
        out.append(SameAs(port, PORTS[port], x, y, tuple(sorted({g[0] for g in got})), example))
    return out


def joint_kinds(scene):
    """The kinds of joint in ``scene``, a body no joint holds counted as a ``free`` joint: a sorted tuple."""
    held = {j.child for j in scene.joints}
    kinds = {j.kind for j in scene.joints}
    if any(b.name not in held for b in scene.bodies):
        kinds.add("free")
    return tuple(sorted(kinds))
