"""Newton's MuJoCo solver (``adapters.newton.mujoco_solver``): its families run in an engine environment of their
own (``dalembert env create newton==1.8.0`` installs ``newton[sim]``), and are refused, before anything is built,
wherever the installed MuJoCo is not the one Newton's ``sim`` extra pins (dalembert's own environment: MuJoCo 4.0).

The refusal and the environment's requirement need no network: a fake environment is a directory whose
site-packages hold the distributions' metadata. The runs in the real environment need it made (34 s and ~850 MB,
once per machine, with the package index); without it they skip, naming the command.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.adapters.newton import mujoco_solver
from dalembert.environments import INFO, environment
from installed import needs

pytestmark = needs("newton", reason="Newton is not installed: pip install dalembert[newton]")

SPEC = "newton==1.8.0"
# Newton 1.8.0's own declaration (its METADATA), as a fake environment's Newton declares it
NEWTON_REQUIRES = ("warp-lang>=1.17.0",
                   "mujoco-warp~=3.17.0 ; (platform_machine != 'ARM64' and extra == 'sim') or "
                   "(sys_platform != 'win32' and extra == 'sim')",
                   "mujoco~=3.17.0 ; (platform_machine != 'ARM64' and extra == 'sim') or "
                   "(sys_platform != 'win32' and extra == 'sim')",
                   "scipy>=1.11.0 ; extra == 'importers'")


def _site(path, **versions):
    """A fake environment at ``path`` whose site-packages hold Newton 1.8.0 (``NEWTON_REQUIRES``) and each
    distribution of ``versions`` (name -> version) as metadata only."""
    site = os.path.join(path, "lib", f"python{sys.version_info[0]}.{sys.version_info[1]}", "site-packages")
    for name, version in {"newton": "1.8.0", **versions}.items():
        info = os.path.join(site, f"{name.replace('-', '_')}-{version}.dist-info")
        os.makedirs(info)
        requires = "".join(f"Requires-Dist: {r}\n" for r in NEWTON_REQUIRES) if name == "newton" else ""
        with open(os.path.join(info, "METADATA"), "w") as f:
            f.write(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n{requires}")
    return path


def test_env_create_hands_the_installer_newton_with_its_extra(tmp_path, monkeypatch, capsys):
    """``dalembert env create newton==1.8.0`` (the installer faked: no network) asks pip for the extra Newton's
    adapter declares, ``newton[sim]==1.8.0``, and the environment says so; another engine's as named."""
    from dalembert import environments
    from dalembert.harness.cli import main

    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    asked = []

    def call(command, what, log):
        if "venv" in command:
            os.makedirs(os.path.join(command[-1], "bin"))
        elif "install" in command:
            asked.append(command[-1])
        return "1.8.0\n"

    monkeypatch.setattr(environments, "_call", call)
    monkeypatch.setattr(environments, "installer", lambda: "pip")
    assert main(["env", "create", SPEC]) == 0
    assert asked == ["newton[sim]==1.8.0"] and environment(SPEC).info()["requirement"] == "newton[sim]==1.8.0"
    assert environment("mujoco==3.6.0").spec.install() == "mujoco==3.6.0"


def test_the_families_are_refused_here_naming_the_command(capsys, tmp_path):
    """In an environment whose MuJoCo is not Newton's pin (dalembert's: 4.0), a MuJoCo-solver family is refused
    before anything is built, naming the command that makes the environment; the other families are not."""
    from importlib import metadata

    from packaging.specifiers import SpecifierSet

    if SpecifierSet("~=3.17.0").contains(metadata.version("mujoco")):
        pytest.skip("this environment holds Newton's MuJoCo: nothing to refuse")
    adapter, case = get_adapter("newton"), make_case("pendulum")
    for family in mujoco_solver.FAMILIES:
        reason = adapter.unsupported_before_build(case.scene, Settings(family, dt=1e-3))
        assert reason and f"dalembert env create {SPEC}" in reason and "mujoco~=3.17.0" in reason, reason
        assert f"mujoco {metadata.version('mujoco')} installed" in reason, reason
    assert adapter.unsupported_before_build(case.scene, Settings("featherstone", dt=1e-3)) is None
    from dalembert.harness.cli import main

    assert main(["run", "--engine", "newton", "--integrator", "mujoco_rk4", "--case", "pendulum", "--quick",
                 "--jobs", "1", "--out", str(tmp_path / "r")]) == 2
    assert f"dalembert env create {SPEC}" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_the_requirement_is_read_from_the_environments_newton(tmp_path):
    """``problem`` reads Newton's ``sim`` requirement and the installed MuJoCo from the environment's own
    site-packages: Newton's pin met, no problem; MuJoCo 4.0 or MuJoCo Warp missing, each named."""
    good = _site(str(tmp_path / "good"), mujoco="3.17.0", **{"mujoco-warp": "3.17.0"})
    assert [str(r) for r in mujoco_solver.requirements(mujoco_solver._sites(good))] == [
        'mujoco-warp~=3.17.0; (platform_machine != "ARM64" and extra == "sim") or '
        '(sys_platform != "win32" and extra == "sim")',
        'mujoco~=3.17.0; (platform_machine != "ARM64" and extra == "sim") or (sys_platform != "win32" and extra == '
        '"sim")']
    assert mujoco_solver.problem(good) is None
    bad = _site(str(tmp_path / "bad"), mujoco="4.0.0")
    why = mujoco_solver.problem(bad)
    assert "mujoco-warp not installed" in why and "mujoco 4.0.0 installed" in why, why


def test_a_versioned_engine_is_judged_by_its_environment(tmp_path, monkeypatch):
    """``--engine newton==1.8.0`` outside its environment: the adapter asks the environment's packages, not this
    process's (``registry._in_environment`` gives it the environment's ``version``)."""
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    env = environment(SPEC)
    _site(env.path, mujoco="3.17.0", **{"mujoco-warp": "3.17.0"})
    with open(os.path.join(env.path, INFO), "w") as f:
        json.dump({"engine": SPEC, "requirement": SPEC, "engine_version": "1.8.0", "python": "", "installer": "fake",
                   "created": "now"}, f)
    scene, settings = make_case("pendulum").scene, Settings("mujoco_rk4", dt=1e-3)
    assert get_adapter(SPEC).unsupported_before_build(scene, settings) is None
    os.rename(os.path.join(mujoco_solver._sites(env.path)[0], "mujoco-3.17.0.dist-info"),
              os.path.join(mujoco_solver._sites(env.path)[0], "mujoco-4.0.0.dist-info"))
    with open(os.path.join(mujoco_solver._sites(env.path)[0], "mujoco-4.0.0.dist-info", "METADATA"), "w") as f:
        f.write("Metadata-Version: 2.1\nName: mujoco\nVersion: 4.0.0\n")
    assert "mujoco 4.0.0 installed" in get_adapter(SPEC).unsupported_before_build(scene, settings)


# ---------------------------------------------------------------- in the real environment
# A pendulum's swing over 0.2 s at dt 1e-3 against its closed form (elliptic functions). RK4's own error there is
# ~1e-13 rad (h^4 over 200 steps), so what remains is float32's: measured 3.2e-7 rad with Newton's MuJoCo solver
# (MuJoCo 3.17.0, Warp's CPU backend); 1e-6 bounds it with room for roundoff elsewhere.
RK4_PENDULUM_TOL = 1e-6
# Semi-implicit Euler's first-order error on the same swing: measured 1.2e-3 rad; above 1e-4 it is a first-order
# method's (g dt t / L ~ 2e-3), not RK4's reached by mistake.
EULER_PENDULUM_MIN = 1e-4


@pytest.mark.long
def test_each_family_runs_in_its_environment_with_its_own_integrator(tmp_path):
    """The three families in the made environment (``dalembert run --engine newton==1.8.0``): each steps with the
    MuJoCo integrator it names (read back from the MuJoCo model), MuJoCo 3.17 under it, no equality added; RK4 at the
    float32 floor, semi-implicit Euler at its first-order error."""
    env = environment(SPEC)
    if not env.exists:
        pytest.skip(f"no environment for {SPEC} — make it (package index) with: dalembert env create {SPEC}")
    from dalembert.harness.cli import main
    from dalembert.store import Store

    out = str(tmp_path / "r")
    args = ["run", "--engine", SPEC, "--case", "pendulum", "--dt", "1e-3", "--param", "t_final=0.2", "--quick",
            "--jobs", "1", "--out", out]
    assert main([*args, *(a for f in mujoco_solver.FAMILIES for a in ("--integrator", f))]) == 0
    records = {r.settings.integrator: r for r in Store(out).records()}
    assert set(records) == set(mujoco_solver.FAMILIES)
    names = {"mujoco_euler": "mjINT_EULER", "mujoco_implicitfast": "mjINT_IMPLICITFAST", "mujoco_rk4": "mjINT_RK4"}
    for family, r in records.items():
        assert r.status == "ok" and r.engine_version == "1.8.0", (family, r.message)
        held = r.audit["solver_settings"]
        assert held["integrator"] == names[family] and held["mujoco_version"].startswith("3.17"), held
        assert held["neq"] == 0 and held["dof_armature_max"] == held["dof_damping_max"] == 0.0, held
    assert records["mujoco_rk4"].max_error("orientation") < RK4_PENDULUM_TOL, records["mujoco_rk4"].errors
    assert records["mujoco_euler"].max_error("orientation") > EULER_PENDULUM_MIN, records["mujoco_euler"].errors
    assert np.isfinite(records["mujoco_implicitfast"].max_error("orientation"))
