"""``dalembert engines``: each registered engine, its version (or why it is not installed), the package
that provides its adapter where it is not dalembert (a plugin), the effects it supports and its integrators
(``verbose``: their options and descriptions). A plugin left out is named in a warning (``adapters.registry``)."""

from __future__ import annotations

__all__ = ["run", "main"]


def run(verbose=False):
    """Print every registered engine; returns the exit status, 0."""
    from dalembert.adapters import adapter_names, get_adapter
    from dalembert.adapters.registry import OWN_DISTRIBUTION, adapter_distribution

    for name in adapter_names():
        adapter = get_adapter(name)
        try:
            version = adapter.version()
        except ImportError as e:
            version = f"not installed ({e})"
        dist, dist_version = adapter_distribution(name)
        plugin = f"  (adapter from {dist} {dist_version})" if dist and dist != OWN_DISTRIBUTION else ""
        print(f"{name:<10} {version}{plugin}")
        print(f"    effects: {', '.join(sorted(adapter.effects))}")
        for integ, spec in adapter.integrators.items():
            knobs = "dt" if spec.fixed_step else "rtol, atol"
            opts = f"; options: {', '.join(spec.options)}" if spec.options and verbose else ""
            print(f"    {integ:<20} {knobs}{opts}  {spec.description if verbose else ''}".rstrip())
        if verbose:  # each option's values, from the adapter's declaration (``Adapter.options``)
            for key, option in adapter.options.items():
                default = "" if option.default is None else f"; default {option.default}"
                only = f"; {', '.join(option.only)} only" if option.only else ""
                print(f"    option {key}: {option.allowed()}{default}{only}  {option.description}".rstrip())
    return 0


def main(args):
    return run(verbose=args.verbose)
