"""The start of a script that runs several ``dalembert`` commands in one fresh interpreter (one start, not one per
command) and keeps what each said: ``command(*args)`` returns ``{"status", "stdout", "stderr"}``. A test appends
its commands, collecting them in a dict it prints as JSON on stdout's last line."""

PRELUDE = """
import contextlib, io, json, sys

from dalembert.harness.cli import main

def command(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(list(args))
    return {"status": status, "stdout": out.getvalue(), "stderr": err.getvalue()}
"""
