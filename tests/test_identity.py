"""One run identity, one file key, one case-version guard (``dalembert.identity``)."""

from dalembert.harness.matrix import RunSpec
from dalembert.identity import check_version, run_identity, run_key
from dalembert.record import RunRecord
from dalembert.settings import Settings


def test_run_keys_are_the_ones_stores_were_written_with():
    """A store is resumed by its runs' keys: these two were computed by dalembert before the key was
    made from ``run_identity`` (commit 7d7e7dc's ``RunSpec.key``), and must not change."""
    fixed = RunSpec("pendulum", "mujoco", Settings("rk4", 1e-3, options={"jacobian": "dense"}), (("t_final", 0.5),),
                    "0123456789ab")
    adaptive = RunSpec("free_top", "reference", Settings("dop853", rtol=1e-6, atol=1e-6), (("t_final", 0.5),),
                       "ba9876543210")
    assert fixed.key == "pendulum__mujoco__rk4__2ca519cdd824"
    assert adaptive.key == "free_top__reference__dop853__1cae016f617a"


def test_a_spec_and_its_record_have_one_identity():
    """``compare`` pairs records by the identity a spec has; the parameters are part of it, the
    case version is not (two versions of a case pair, and are then refused by the version guard)."""
    spec = RunSpec("pendulum", "mujoco", Settings("rk4", 1e-3, options={"jacobian": "dense"}), (("t_final", 0.5),),
                   "v1")
    record = RunRecord("k", "pendulum", "v2", "mujoco", Settings("rk4", 1e-3, options={"jacobian": "dense"}),
                       params={"t_final": 0.5}, status="ok")
    assert spec.identity == run_identity(record.case, record.params, record.engine, record.settings)
    other = run_identity("pendulum", {"t_final": 1.0}, "mujoco", Settings("rk4", 1e-3, options={"jacobian": "dense"}))
    assert other != spec.identity
    # within a store the case version stands for the parameters: another version is another file
    assert run_key(spec.identity, "v2") != spec.key


def test_the_version_guard_names_the_case_and_both_versions():
    assert check_version("pendulum", "aaa", "aaa", "the matrix was made for") is None
    said = check_version("pendulum", "aaa", "bbb", "the matrix was made for")
    assert said == "case 'pendulum' is version bbb now, the matrix was made for version aaa"
