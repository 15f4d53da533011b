"""``dalembert cases``: the registered cases, their tags and summaries (``verbose``: parameters,
defaults and units)."""

from __future__ import annotations

__all__ = ["run", "main"]


def run(verbose=False):
    """Print every registered case; returns the exit status, 0."""
    from dalembert.case import load_cases

    for name, factory in load_cases().items():
        print(f"{name:<24} [{', '.join(factory.tags)}]  {factory.summary}")
        if verbose:
            for key, default in factory.params.items():
                unit = factory.units.get(key, "")
                print(f"    {key:<18} = {default!r}" + (f"  ({unit})" if unit else ""))
    return 0


def main(args):
    return run(verbose=args.verbose)
