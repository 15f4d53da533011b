"""The catalogue of validation cases: one module per case family.

Every module here is imported by ``dalembert.case.load_cases()``; a module
registers its factories with ``@case``. Add a case by adding a module.
"""
