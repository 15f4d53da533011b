"""``python -m dalembert.harness.worker``: run one spec read (pickled: spec, timing, truth
npz) from stdin, write the pickled ``(RunRecord, trajectory npz)`` to stdout. Used to
isolate runs on Dask workers."""

import pickle
import sys

from dalembert.harness.execute import Timing, execute
from dalembert.harness.lifetime import die_with_parent
from dalembert.harness.matrix import RunSpec
from dalembert.store import trajectory_from_npz


def main():
    request = pickle.loads(sys.stdin.buffer.read())
    die_with_parent(request["parent"])
    truth = trajectory_from_npz(request["truth"]) if request["truth"] is not None else None
    result = execute(RunSpec.from_json(request["spec"]), Timing(**request["timing"]), truth)
    sys.stdout.buffer.write(pickle.dumps(result))


if __name__ == "__main__":
    main()
