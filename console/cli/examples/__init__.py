"""Built-in examples run by ``swarmdeck example NAME``, one module each.

An example module defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and
``main(args) -> int``, like a CLI command (:mod:`swarmdeck.console.cli`). They are thin: the
experiment is in :mod:`swarmdeck.examples`, the shared run plumbing in
:mod:`swarmdeck.console.cli.run` and :func:`swarmdeck.console.cli.example.run_example`.
"""
