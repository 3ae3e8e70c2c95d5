"""Built-in examples run by ``swarmdeck example NAME``, one module each.

An example module defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and
``main(args) -> int``, like a CLI command (:mod:`swarmdeck.console.cli`).
"""
