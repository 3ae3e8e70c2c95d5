"""The root of swarmdeck's own exceptions.

Every exception class swarmdeck defines derives from :class:`SwarmdeckError` *and* keeps the builtin base it
always had (``ConfigError`` is still a ``ValueError``, ``SetupFailed`` a ``RuntimeError``), so ``except
SwarmdeckError`` catches anything swarmdeck raised on purpose while existing ``except ValueError`` clauses keep
working. Two control-flow signals are deliberately not errors and do not derive from it:
``devices.ExperimentFinished`` (an experiment's normal end) and ``console.sandbox.verification.VerificationCancelled``.
``tests/core/test_core_errors.py`` checks the rule over the whole source tree.
"""
from __future__ import annotations

__all__ = ["SwarmdeckError"]


class SwarmdeckError(Exception):
    """Something swarmdeck refused or could not do; the message names what was wrong."""
