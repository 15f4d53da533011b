"""Engine adapters: one interface, many engines, chosen by name.

The contract — every adapter class:

1. is registered under a lowercase engine name: built-in ones in ``BUILTIN``
   (``"module:Class"``, imported only when asked for), third-party ones
   through the entry-point group ``dalembert.adapters``;
2. imports its engine lazily, inside its methods, so listing and help work
   without it; ``version()`` returns the engine's version (and raises
   ImportError when the engine is missing); ``load()`` imports all of the
   engine a run uses (default: what ``version()`` imports), which a pool's
   worker calls before its first run, so that no run's time holds an import;
3. declares ``effects``: the ``Scene.effects`` tags it can represent. A scene
   that needs another effect is not run: the harness lists it refused with the
   reason (in the matrix's manifest; a run stored ``unsupported`` where only the
   built model shows it) — never a silent approximation;
4. declares ``integrators``: name -> ``IntegratorSpec`` (fixed-step or
   adaptive, and the names of the engine options it accepts), and ``options``:
   name -> ``Option`` (the values each option takes and its default), the one
   place an option's values and default are written (a run's value is read
   with ``Adapter.option``: the given one, else the declared default);
   ``variants(scene)`` lists the
   option sets the default matrix runs on a scene (e.g. each formulation);
5. ``check(scene, times, settings)`` raises ValueError naming the field for
   settings it cannot run (unknown option or value — the base class checks
   every one against ``options`` —, dt that does not divide the sample
   interval, ...) — cheap, called before anything runs; ``unsupported(scene,
   settings)`` returns the reason a valid request cannot be represented, or None,
   and ``unsupported_before_build(scene, settings)`` the part of it known without
   building the model (default: all of it; the matrix lists those refusals once
   in its manifest instead of expanding them into runs);
   ``describe(scene, settings)`` returns the model it would build, as text
   (``""``: none);
6. ``prepare(scene, times, settings)`` builds the engine model (not timed) and
   returns it as a ``Prepared`` (a frozen dataclass: the engine's subclass
   documents each field, read as attributes);
7. ``run(prepared)`` simulates from the initial state and samples at exactly
   ``times``, returning an ``Outcome``: the wall time of the stepping alone,
   steps and right-hand-side evaluations, and a ``read_back`` that turns the
   sampled engine states into a ``Trajectory`` in body terms (converted
   through ``dalembert.spatial`` only). The read-back runs once, when the
   outcome's ``trajectory`` is first used, so the harness's timed repeats pay
   for stepping only; everything that is not stepping (building, loading a
   compiled library) belongs in ``prepare``. ``run`` can be called repeatedly
   on one prepared model and gives identical results each time (the harness
   warms up once, then repeats for timing). A run that diverges returns NaN
   from the point of divergence on, never an exception;
8. ``audit(prepared, outcome)`` returns what the engine actually simulated,
   read back from the engine: gravity vector, loads, joints, constraint rows,
   contacts, passive forces, the integrator as the engine names it;
9. writes no files and prints nothing.

``check_adapter(name)`` runs this contract on every registered case the
adapter supports.

Modules: ``base`` (the ``Adapter`` base class and what it returns),
``registry`` (``BUILTIN``, engines by name), ``contract`` (``check_adapter``);
one module or package per engine: ``reference``, ``mujoco``, ``pinocchio``,
``exudyn``.
"""

from dalembert.adapters.base import Adapter, IntegratorSpec, Option, Outcome, Prepared
from dalembert.adapters.contract import check_adapter
from dalembert.adapters.registry import BUILTIN, adapter_names, adapter_path, get_adapter, register_adapter

__all__ = ["Adapter", "IntegratorSpec", "Option", "Outcome", "Prepared", "BUILTIN", "adapter_names", "adapter_path", "get_adapter",
           "register_adapter", "check_adapter"]
