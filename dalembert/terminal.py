"""Text from a store, made safe to print on a terminal.

A store is a directory of files anyone may have edited: an engine name, a case
name, a run's message or a lock file's holder may carry control characters, and
an escape sequence printed as it is moves the cursor, clears the screen or
retitles the window. ``printable`` shows them instead, as Python writes them in
a string (``\\x1b``, ``\\r``): the text is still readable, and what was odd in it
is visible. Everything the command line prints that came from a store goes
through it; files a command writes (JSON, CSV) keep the text as stored.
"""

from __future__ import annotations

import re

__all__ = ["printable"]

# C0 (U+0000-U+001F, ESC among them), DEL (U+007F) and C1 (U+0080-U+009F: U+009B is a one-character CSI on
# terminals that take 8-bit controls). Tab and newline are matched too; ``printable`` keeps them when asked.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")
_NAMED = {"\t": "\\t", "\n": "\\n", "\r": "\\r"}


def _escaped(match):
    c = match.group()
    return _NAMED.get(c) or f"\\x{ord(c):02x}"


def printable(text, newlines=True):
    """``text`` with every control character replaced by its visible escape.

    Parameters
    ----------
    text : str
        Text that came from a store (any object: it is formatted with ``str``).
    newlines : bool
        Keep newline and tab as they are (text of several lines); False escapes them too
        (one line of a table: a name with a newline in it must not break the table).

    Returns
    -------
    str
        ``text`` with C0 controls (ESC, CR, ...), DEL and C1 controls written as ``\\x1b``,
        ``\\r``, ``\\x7f``, ``\\x9b``; unchanged when it has none.
    """
    text = str(text)
    if newlines:
        return _CONTROL.sub(lambda m: m.group() if m.group() in "\n\t" else _escaped(m), text)
    return _CONTROL.sub(_escaped, text)
