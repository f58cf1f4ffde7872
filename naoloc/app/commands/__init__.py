"""One module per CLI verb: ``naoloc.app.commands.<verb>.run(args, config) -> dict``.

``run`` prints any human-readable text to stdout itself and returns the JSON
summary, which :mod:`naoloc.app.cli` prints as the last line of stdout.
"""
