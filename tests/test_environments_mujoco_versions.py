"""What changed between MuJoCo's releases, as docs/engines.md tells it, checked by its reproduction
(``docs/mujoco_jdotv_four_bar.py``): from 3.7.0 the equality rows' reference acceleration carries -J̇v, and that
term is the whole of the four-bar's change under RK4 (3.6.0 stepped with 3.7.0's rule runs as 3.7.0 does)."""

from __future__ import annotations

import os
import runpy

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

SCRIPT = runpy.run_path(os.path.join(os.path.dirname(__file__), "..", "docs", "mujoco_jdotv_four_bar.py"))
# The hand RK4 repeats mj_step's arithmetic in its order; what differs is J̇v's, summed by mj_jacDot here and by
# mj_Jdotv there (measured: 4.9e-13 rad on the crank over the 0.5 s).
SAME_RUN = 1e-10  # rad
# The rule's effect on the crank at dt = 5e-3 (measured: 3.8e-5 rad against 2.0e-6): a tenth of it is no noise.
DIFFERENT_RUN = 3e-6  # rad


def _versions_of(results):
    return {mode: np.array(results[mode][2]) for mode in SCRIPT["MODES"]}


@pytest.mark.skipif(tuple(int(x) for x in mujoco.__version__.split(".")[:2]) < (3, 7),
                    reason="the installed MuJoCo is older than 3.7.0, which added the term")
def test_the_installed_mujoco_steps_the_four_bar_with_the_jdotv_rule():
    crank = _versions_of(SCRIPT["runs"](5e-3))
    assert np.abs(crank["mj_step"] - crank["new"]).max() < SAME_RUN
    assert np.abs(crank["mj_step"] - crank["old"]).max() > DIFFERENT_RUN


def _cached(version):
    from dalembert.environments import environment

    env = environment(f"mujoco=={version}")
    if not env.exists or env.stale():
        pytest.skip(f"no usable environment of mujoco=={version} in this cache (dalembert env create "
                    f"mujoco=={version} makes one; it needs the package index, so no test makes it)")


def test_mujoco_3_6_0_given_3_7_0s_rule_runs_the_four_bar_as_3_7_0_and_3_7_0_given_3_6_0s_as_3_6_0():
    _cached("3.6.0")
    _cached("3.7.0")
    old, new = SCRIPT["in_environment"]("3.6.0"), SCRIPT["in_environment"]("3.7.0")
    assert (old["version"], new["version"]) == ("3.6.0", "3.7.0")
    old, new = _versions_of(old), _versions_of(new)
    assert np.abs(old["mj_step"] - new["mj_step"]).max() > DIFFERENT_RUN  # the change
    assert np.abs(old["mj_step"] - old["old"]).max() < SAME_RUN  # each release is its own rule
    assert np.abs(new["mj_step"] - new["new"]).max() < SAME_RUN
    assert np.abs(old["new"] - new["mj_step"]).max() < SAME_RUN  # and the rule is the whole change
    assert np.abs(new["old"] - old["mj_step"]).max() < SAME_RUN
