"""Reading and writing the tracker's small JSON files (calibration, tracker config) with clear errors."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def read_json_object(path: str | Path, what: str, error: type[Exception]) -> dict[str, Any]:
    """The JSON object in ``path``; raises ``error`` naming ``what`` and the path when the file is
    missing, unreadable, not UTF-8 text, not JSON, or not an object."""
    try:
        d = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not a text (JSON) file") from exc
    except json.JSONDecodeError as exc:
        raise error(f"{what} {path} is not JSON: {exc}") from exc
    if not isinstance(d, dict):
        raise error(f"{what} {path} must hold a JSON object, got {type(d).__name__}")
    return d


def write_json(path: str | Path, obj: Any, what: str, error: type[Exception]) -> None:
    """Write ``obj`` as indented JSON; raises ``error`` naming ``what`` and the path when it cannot."""
    try:
        Path(path).write_text(json.dumps(obj, indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise error(f"cannot write {what} {path}: {exc.strerror or exc}") from exc
