"""A benchmark's module, imported from the checkout for a test: ``benchmarks/`` is not an installed package (the
suite runs with ``-P``), so it is on ``sys.path`` only while the test holds it."""

import contextlib
import importlib
import os
import sys

__all__ = ["benchmark"]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the checkout, above benchmarks/


@contextlib.contextmanager
def benchmark(name):
    """``benchmarks.<name>``, imported with the checkout on ``sys.path`` for the block's duration."""
    sys.path.insert(0, ROOT)
    try:
        yield importlib.import_module(f"benchmarks.{name}")
    finally:
        sys.path.remove(ROOT)
