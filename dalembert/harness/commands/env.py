"""``dalembert env create|list|remove``: engine environments, an engine at a version of its own
(``dalembert.environments``). ``create`` is the one command that reaches the package index; ``run``
refuses a versioned engine whose environment is missing, naming this command."""

from __future__ import annotations

import sys

__all__ = ["run", "main"]


def run(action, engine=None, verbose=False, force=False):
    """Do ``action`` (``create``, ``list``, ``remove``) for ``engine`` (``mujoco==3.6.0``; none for ``list``);
    returns the exit status. ``force``: ``create`` makes an existing environment again (a stale one). ValueError
    naming the engine for a bad name, a missing or an existing environment."""
    from dalembert import environments
    from dalembert.adapters import get_adapter
    from dalembert.harness.commands.console import fail

    if action == "list":
        made = environments.environments()
        if not made:
            print("no engine environments (make one with: dalembert env create ENGINE==VERSION)")
        for name, info, path in made:
            try:
                stale = environments.Environment(environments.parse_engine(name), path).stale()
            except ValueError as e:  # made by another dalembert that runs this engine at a version; this one cannot
                print(f"{name:<24} {info.get('engine_version', '?'):<10} not runnable by this dalembert: "
                      f"{str(e).partition(': ')[2]}" + (f"\n    {path}" if verbose else ""))
                continue
            print(f"{name:<24} {info['engine_version']:<10} python {info['python']}, {info['installer']}, "
                  f"{info['created']}" + (f"\n    {path}" if verbose else "")
                  + (f"\n    stale: {'; '.join(stale)} — remake it: dalembert env create --force {name}"
                     if stale else ""))
        return 0
    if action == "remove":
        env = environments.remove(engine)
        print(f"removed {env.spec.name} ({env.path})")
        return 0
    env = environments.environment(engine)
    if env.exists and not force:
        raise ValueError(f"env create {engine}: already made, at {env.path} (engine {env.engine_version}) — use it, "
                         f"or make it again: dalembert env create --force {env.spec.name}")
    tool = environments.installer()
    print(f"dalembert: making the environment of {engine} with {'uv' if tool == 'uv' else 'venv and pip'} "
          "(this reaches the package index)", file=sys.stderr)
    try:
        env = environments.create(engine, log=(lambda line: print(f"  {line}", file=sys.stderr)) if verbose
                                  else (lambda line: None), tool=tool,
                                  problem=get_adapter(env.spec.engine).version_problem, force=force,
                                  extras=getattr(get_adapter(env.spec.engine), "environment_extras", ()))
    except RuntimeError as e:  # the installer's own failure (no such version, no network): its output said
        return fail(str(e))
    print(f"made {env.spec.name}: {env.spec.distribution} {env.engine_version} at {env.path}")
    print(f"run it with: dalembert run --engine {env.spec.name} ...")
    return 0


def main(args):
    if args.env_action != "list" and args.engine is None:
        raise ValueError(f"env {args.env_action}: no engine — write e.g. dalembert env {args.env_action} "
                         "mujoco==3.6.0")
    return run(args.env_action, getattr(args, "engine", None), getattr(args, "verbose", False),
               getattr(args, "force", False))
