"""The command line: ``naoloc`` and one module per verb (``naoloc.app.commands``)."""
