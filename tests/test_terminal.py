"""Text from a store reaches the terminal with its control characters shown, not obeyed: an engine
name carrying an escape sequence (clear the screen, retitle the window) is printed escaped by the
command line's errors and by ``compare``'s table."""

import shutil
from dataclasses import replace

import pytest

from dalembert.harness.cli import main
from dalembert.store import Store
from dalembert.terminal import printable
from stores import small_store, tamper

CLEAR = "\x1b[2J\x1b[H"  # ESC [2J ESC [H: clear the screen, cursor home
TITLE = "\x1b]0;owned\x07"  # OSC 0: set the window's title, ended by BEL


@pytest.mark.parametrize("text,shown", [
    ("plain text, unicode é ✓", "plain text, unicode é ✓"),
    (f"ref{CLEAR}", "ref\\x1b[2J\\x1b[H"),
    (TITLE, "\\x1b]0;owned\\x07"),
    ("a\rb\x7fc\x9bd\x00", "a\\rb\\x7fc\\x9bd\\x00"),  # CR, DEL, C1's one-character CSI, NUL
    ("two\nlines\tand a tab", "two\nlines\tand a tab"),
])
def test_control_characters_are_shown_escaped(text, shown):
    assert printable(text) == shown


def test_one_line_escapes_newlines_and_tabs_too():
    assert printable("a\nb\tc", newlines=False) == "a\\nb\\tc"


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """A store, and its copy whose first run's engine name and message carry escape sequences."""
    a = small_store(tmp_path_factory.mktemp("a"), cases=("pivoted_rod",), integrators=("rk4",), dts=(1e-2,),
                    t_final=0.2)
    path = tmp_path_factory.mktemp("b") / "b"
    shutil.copytree(a.path, path)
    b = Store.open(path)
    tamper(b, lambda r: replace(r, engine=f"ref{CLEAR}", message=TITLE))
    return a, b


def test_compare_prints_a_stored_escape_sequence_escaped(stores, capsys):
    a, b = stores
    main(["compare", a.path, b.path])
    out = capsys.readouterr().out
    assert "ref\\x1b[2J\\x1b[H" in out  # the run is listed (only in B), its name shown
    assert "\x1b" not in out and "\x07" not in out


def test_an_error_naming_stored_runs_is_escaped(stores, capsys):
    assert main(["export", stores[1].path, "--engine", "nope", "--csv", "-"]) == 2
    err = capsys.readouterr().err
    assert "ref\\x1b[2J\\x1b[H" in err  # among the stored runs it lists
    assert "\x1b" not in err and "\x07" not in err
