"""swarmdeck.safety: barrier certificates that keep the robots apart and inside the arena.

``SafetyFilter(BarrierConfig()).filter(points, nominal, obstacles=None) -> (safe, diag)``
for single-integrator controlled points (look-ahead points), and
``UnicycleSafetyFilter().filter(poses, v, w, obstacles=None) -> (v, w, diag)``
for unicycle robots with wheel limits (REFERENCE.md §3, paper §IV-B);
``verify(x0, controller, steps)`` scores a closed loop by simulation (REFERENCE.md §4);
:mod:`.guard` watches a run whose barrier an operator let it bypass (``GuardConfig``).
"""
from swarmdeck.core.kinematics import UnicycleParams

from .config import BarrierConfig
from .diagnostics import BarrierDiagnostics
from .filter import SafetyFilter
from .guard import GuardCheck, GuardConfig
from .unicycle import UnicycleSafetyFilter
from .verifier import VerificationReport, verify

__all__ = [
    "BarrierConfig",
    "BarrierDiagnostics",
    "GuardCheck",
    "GuardConfig",
    "SafetyFilter",
    "UnicycleParams",
    "UnicycleSafetyFilter",
    "VerificationReport",
    "verify",
]
