"""The catalogue of built-in cases: one module per case family.

This package is the entry point ``builtin`` of the group ``dalembert.cases``
(``pyproject.toml``), the same group third-party case packages use: loading it
imports every module here, and each module registers its factories with
``@case``. Add a case by adding a module; no list to maintain.
"""

import importlib
import pkgutil

for _info in pkgutil.iter_modules(__path__):
    if not _info.name.startswith("_"):
        importlib.import_module(f"{__name__}.{_info.name}")
