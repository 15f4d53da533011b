"""The report's sections: one module each, each with one function that takes the report's data
(``common.Report``, and for a case's own sections its findings) and returns a ``page.Part``."""
