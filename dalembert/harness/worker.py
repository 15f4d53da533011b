"""``python -m dalembert.harness.worker``: run one spec read as JSON on stdin, write the
pickled ``(row, trajectory_npz)`` to stdout. Used to isolate runs on Dask workers."""

import json
import pickle
import sys

from dalembert.harness.run import RunSpec, Timing, execute


def main():
    request = json.loads(sys.stdin.buffer.read())
    result = execute(RunSpec.from_json(request["spec"]), Timing(**request["timing"]))
    sys.stdout.buffer.write(pickle.dumps(result))


if __name__ == "__main__":
    main()
