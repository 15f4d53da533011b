"""Name -> object registries filled by decorators, with "did you mean" errors."""

from __future__ import annotations

import difflib

__all__ = ["Registry", "UnknownNameError", "suggest"]


def suggest(name, candidates):
    """`` — did you mean 'x'?`` (or the list of known names) for an error message."""
    close = difflib.get_close_matches(str(name), sorted(candidates), n=1)
    return f" — did you mean {close[0]!r}?" if close else f" — known: {', '.join(sorted(candidates))}"


class UnknownNameError(KeyError):
    """A name that is not registered; the message suggests the closest one."""

    def __str__(self):
        return str(self.args[0])


class Registry:
    """A mapping of names to registered objects.

    Parameters
    ----------
    kind : str
        What is registered ("case", "integrator", ...), for error messages.
    """

    def __init__(self, kind):
        self.kind = kind
        self._items = {}

    def register(self, name, obj):
        if name in self._items:
            raise ValueError(f"{self.kind} {name!r} is registered twice")
        self._items[name] = obj
        return obj

    def __getitem__(self, name):
        try:
            return self._items[name]
        except KeyError:
            raise UnknownNameError(f"unknown {self.kind} {name!r}{suggest(name, self._items)}") from None

    def __contains__(self, name):
        return name in self._items

    def __iter__(self):
        return iter(sorted(self._items))

    def __len__(self):
        return len(self._items)

    def items(self):
        return sorted(self._items.items())
