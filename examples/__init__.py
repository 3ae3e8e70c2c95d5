"""Example experiments written against the public API, the way a new user would copy them.

Run one with ``swarmdeck run examples/rendezvous.py`` or ``swarmdeck example rendezvous``.
"""
