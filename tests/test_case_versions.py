"""Every built-in case's version hash at its default parameters, pinned.

A case's version (``Case.version``) is the content hash of everything that defines the problem and
judges a run: scene, horizon, sample times, parameters, tolerance values, conserved quantities,
declared invariants. A store keeps runs under it, and a run of another version is another problem.
Comparing a newly made case with another newly made one cannot see a change to a case's content;
this literal can: when a case's hash changes, its stored results become another version.

A change here must be deliberate. Regenerate the literal with::

    python -c "from dalembert.case import load_cases; print({n: f().version for n, f in sorted(load_cases().items())})"

and say in the commit which case changed and why its stored results become another version.
A new built-in case gets its line here.
"""

import importlib.metadata

import pytest

from dalembert.case import CASES, load_cases, make_case

load_cases()

VERSIONS = {
    "andrews_squeezer": "a3b07d6b2529",
    "ball_rolling_incline": "6dabc3383a8f",
    "ball_slide_to_roll": "296c844d86ec",
    "block_on_incline": "aac4169ede93",
    "bouncing_ball": "573c5418d418",
    "bricard": "7c2b8c4a437c",
    "chain": "8049d7d884a4",
    "chain_chaotic": "e4af1066c068",
    "flyball_governor": "e0b1e67b12c0",
    "four_bar": "72650d65149f",
    "free_top": "b0b4cb11c390",
    "free_top_fast_spin": "733f4896d60b",
    "free_top_intermediate": "96851d9b1bff",
    "free_top_long_horizon": "572ee138239e",
    "free_top_near_symmetric": "3ff8dc4fd472",
    "free_top_separatrix": "b54fd48c5fdd",
    "free_top_slender": "7748b0ac3603",
    "heavy_top": "70fe3e2d1085",
    "heavy_top_nutating": "45ed74d4cc47",
    "kovalevskaya_top": "a3b0fd533941",
    "n_four_bar": "22988d08d2e1",
    "particle_box": "c8b418657722",
    "particle_box_welded": "9059341be142",
    "pendulum": "e47c4306ecf5",
    "pendulum_a01": "2c05611bb412",
    "pivoted_rod": "da2a01182e34",
    "pivoted_rod_violent": "ede03c9c63ec",
    "robot_arm": "f5e15ac70a60",
    "robot_free_fall": "2583c21e5052",
    "robot_tree": "41b237ef23a6",
    "sphere_collision": "a49d0f5e1e88",
}


def test_every_built_in_case_is_pinned():
    built_in = {n for n, f in CASES.items() if f.func.__module__.startswith("dalembert.cases.")}
    assert built_in == set(VERSIONS), (f"not pinned: {sorted(built_in - set(VERSIONS))}; "
                                       f"pinned but gone: {sorted(set(VERSIONS) - built_in)}")


# The robot cases read their robots from example-robot-data (the ``robots`` extra): without it they refuse to be
# made, so their pins are checked only where it is installed.
ROBOT_CASES = ("robot_arm", "robot_free_fall", "robot_tree")


def _have(distribution):
    try:
        importlib.metadata.distribution(distribution)
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


@pytest.mark.parametrize("name", sorted(VERSIONS))
def test_the_version_at_the_defaults_is_as_pinned(name):
    if name in ROBOT_CASES and not _have("example-robot-data"):
        pytest.skip("example-robot-data not installed (pip install dalembert[robots])")
    assert CASES[name]().version == VERSIONS[name], (
        f"{name}: its content changed, so its stored results are of another version — if that is meant, "
        "update VERSIONS (see the module docstring) and say why in the commit")


def test_a_case_built_with_an_int_parameter_is_not_handed_out_for_the_same_value_as_a_float():
    """500 == 500.0 and they hash alike, but the version hashes the parameters as given: the per-process cache of
    built cases must not answer one with the other (a matrix then refused its own runs as another version)."""
    from dalembert.harness.truths import built_case

    params = {"t_final": 0.5, "sample_interval": 0.1}
    as_int = built_case("free_top_fast_spin", {**params, "spin": 500})
    as_float = built_case("free_top_fast_spin", {**params, "spin": 500.0})
    assert as_float[1] == make_case("free_top_fast_spin", **params, spin=500.0).version
    assert as_int[1] == make_case("free_top_fast_spin", **params, spin=500).version
