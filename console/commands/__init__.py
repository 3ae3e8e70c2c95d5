"""Subcommands of the ``swarmdeck`` CLI, one module each (see :mod:`swarmdeck.console.cli`)."""
