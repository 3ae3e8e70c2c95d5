"""The network's refusals: each names the robot, the tick and what was wrong (REFERENCE.md §16)."""
from __future__ import annotations

from swarmdeck.core.errors import SwarmdeckError

__all__ = ["IsolationError", "MessageError", "PayloadError"]


class MessageError(ValueError, SwarmdeckError):
    """A message the network refused: unknown or own receiver, too big, too many in one tick."""


class PayloadError(MessageError, TypeError):
    """A payload that is not serialisable as the network defines it (:mod:`swarmdeck.network.payload`)."""


class IsolationError(PermissionError, SwarmdeckError):
    """A decentralised controller reached for something a robot cannot know (another robot's pose, the arena)."""
