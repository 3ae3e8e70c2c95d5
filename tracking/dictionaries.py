"""The marker dictionaries: every predefined OpenCV ArUco dictionary and the AprilTag
families OpenCV detects, by name.

Canonical names are OpenCV's constants (``DICT_4X4_50`` … ``DICT_7X7_1000``,
``DICT_ARUCO_ORIGINAL``, ``DICT_ARUCO_MIP_36h12``, ``DICT_APRILTAG_16h5``, ``_25h9``,
``_36h10``, ``_36h11``). Names are matched case-insensitively, with or without the
``DICT_`` prefix; AprilTag families may also be given as ``tag36h11``.
"""
from __future__ import annotations

from types import MappingProxyType

import cv2

_SIZES = ("4X4", "5X5", "6X6", "7X7")
_COUNTS = ("50", "100", "250", "1000")
_NAMES = ([f"DICT_{s}_{n}" for s in _SIZES for n in _COUNTS]
          + ["DICT_ARUCO_ORIGINAL", "DICT_ARUCO_MIP_36h12", "DICT_APRILTAG_16h5", "DICT_APRILTAG_25h9",
             "DICT_APRILTAG_36h10", "DICT_APRILTAG_36h11"])

#: Read-only canonical name → OpenCV predefined-dictionary id.
DICTIONARIES: MappingProxyType = MappingProxyType({n: int(getattr(cv2.aruco, n)) for n in _NAMES})

_BY_KEY = {n.upper(): n for n in DICTIONARIES}


def canonical_dictionary(name: str) -> str:
    """The canonical name of dictionary ``name`` (e.g. ``"apriltag_36h11"`` →
    ``"DICT_APRILTAG_36h11"``). Raises ValueError listing the valid names."""
    key = str(name).strip().upper() if isinstance(name, str) else ""
    if key.startswith("TAG") and key[3:4].isdigit():
        key = "APRILTAG_" + key[3:]
    if key and not key.startswith("DICT_"):
        key = "DICT_" + key
    found = _BY_KEY.get(key)
    if found is None:
        raise ValueError(f"unknown marker dictionary {name!r}; valid (case-insensitive): {', '.join(_NAMES)}")
    return found


def dictionary(name: str) -> cv2.aruco.Dictionary:
    """The predefined OpenCV dictionary called ``name`` (any spelling :func:`canonical_dictionary` accepts)."""
    return cv2.aruco.getPredefinedDictionary(DICTIONARIES[canonical_dictionary(name)])
