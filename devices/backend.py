"""What the experiment API needs from the robots it drives (its synchronous view of them).

:class:`RobotBackend` is the ``Arena``'s role in the robot-port vocabulary of
:mod:`swarmdeck.core.ports`: ``poses``, ``time`` and ``step(v, w)``, which applies
one unicycle command per robot and advances one period. The simulated arena
satisfies it; ``devices.net.transport_backend.TransportBackend`` gives the same
calls for real GRITSBots (a ``RobotTransport`` and its ``PoseFeed``), so a user's
experiment runs unchanged on either.
"""
from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import GritsBotParams


@runtime_checkable
class RobotBackend(Protocol):
    """Robots that report poses and take one unicycle command per period."""

    n_robots: int
    params: GritsBotParams

    @property
    def poses(self) -> NDArray[np.float64]:
        """Current poses ``(N, 3)`` (a copy)."""

    @property
    def time(self) -> float:
        """Seconds since the start of the run on this backend's clock."""

    def step(self, v: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """Apply ``(v, ω)`` for one period and return the new poses.

        (A backend may instead define ``step_nominal(nominal)`` taking the nominal look-ahead
        velocities ``(N, 2)`` before any limit or filter: :meth:`Arena.step` then hands them over
        as they are — for robots whose commands are certified elsewhere, as a sandboxed script's are.)"""
