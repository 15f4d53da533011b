"""Workers started as their own interpreter.

``python -m dalembert.harness.worker``: run one spec read (pickled: spec, timing, truth
npz, the engine environment it was started for, if any, and the trajectories the store keeps,
``harness.sent.Sent``) from stdin, write the pickled ``(RunRecord, trajectory npz or None)`` to stdout. Used to isolate runs on Dask workers.

``serve()``: a pool's long-lived worker in an engine environment's interpreter
(``dalembert.harness.pool._Interpreter`` starts it), reading its settings as JSON from
``sys.argv[1]``: ``fd`` (its end of the pool's pipe, a socket), ``parent`` (the pool's
pid), ``threads``, ``engines`` (``[name, "module:Class"]`` pairs) and ``environment`` (the
directory of the environment it was started for: its versioned engine runs here); it then
serves the pool's protocol (``pool._serve``) as a forked worker does.
"""

import json
import pickle
import sys

from dalembert.harness.execute import Timing, execute
from dalembert.harness.lifetime import die_with_parent
from dalembert.harness.matrix import RunSpec
from dalembert.store import trajectory_from_npz


def main():
    request = pickle.loads(sys.stdin.buffer.read())
    die_with_parent(request["parent"])
    if request.get("environment"):  # started for an engine environment: its versioned engine runs here
        from dalembert.environments import serving

        serving(request["environment"])
    truth = trajectory_from_npz(request["truth"]) if request["truth"] is not None else None
    result = execute(RunSpec.from_json(request["spec"]), Timing(**request["timing"]), truth, sent=request.get("sent"))
    sys.stdout.buffer.write(pickle.dumps(result))


def serve():
    """A pool's worker in this interpreter, on the pipe and settings ``sys.argv[1]`` names (module docstring)."""
    from multiprocessing.connection import Connection

    from dalembert.harness.pool import _serve

    from dalembert.environments import serving

    settings = json.loads(sys.argv[1])
    serving(settings["environment"])
    _serve(Connection(settings["fd"]), settings["parent"], settings["threads"],
           tuple(tuple(e) for e in settings["engines"]))


if __name__ == "__main__":
    main()
