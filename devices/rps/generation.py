"""Which Robotarium Python simulator a script was written for: rps 1.x (the ``dev`` branch) or 2.x (``master``).

The two generations share ``import rps.robotarium`` and most names but model different robots (1.x the GRITSBot,
2.x the GTernal, REFERENCE.md §15) and end differently: every 1.x script ends with
``r.call_at_scripts_end()``, every 2.x script with ``r.debug()`` (2.x removed ``call_at_scripts_end``). The
runner reads the script's source once and hands the answer to the facade (``RunDefaults.rps_generation``), which
then picks the robot model the script expects; ``swarmdeck run --rps-generation 1|2`` or
``--robot-model`` overrides it.
"""
from __future__ import annotations

import re
from typing import Literal

from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL

Generation = Literal[1, 2]

_ONE = re.compile(r"\.\s*call_at_scripts_end\s*\(")
_TWO = re.compile(r"\.\s*debug\s*\(\s*\)")


def script_generation(source: str) -> Generation | None:
    """1 when ``source`` calls ``call_at_scripts_end()``, 2 when it calls ``debug()`` and not that, else None
    (neither: the facade keeps the arena's robot model)."""
    if _ONE.search(source):
        return 1
    if _TWO.search(source):
        return 2
    return None


def robot_model_for(source: str) -> str:
    """The robot model an rps script of this ``source`` expects: ``"gternal"`` for a 2.x script, else the default
    (``"gritsbot"``, :data:`~swarmdeck.core.robot_models.DEFAULT_ROBOT_MODEL`)."""
    return "gternal" if script_generation(source) == 2 else DEFAULT_ROBOT_MODEL
