"""The ``dalembert`` commands, one module each: ``cases``, ``engines``, ``truth``, ``run``,
``report``, ``export``, ``compare``, ``show_model``, ``validate``.

Each module's ``run(...)`` does the command from keywords named as its flags (``--no-maps`` is
``no_maps``; a repeatable flag's keyword is its plural: ``--case`` is ``cases``) and checks every
input before anything is written; ``main(args)`` is the command line's use of it (an argparse
namespace in, an exit status out). ``dalembert.harness.cli`` only builds the parser and
dispatches; ``dalembert.harness.api`` is these ``run``\\ s for Python.
"""
