"""The review's small findings stay gone (issue 25 item 6): each REFERENCE.md number is named once in
core/constants.py, the robot's motion is defined once in core/kinematics.py, service threads are started
through core.service_thread only, and the tests get the shared fixtures from tests/conftest.py.

Read with ``tokenize``/``ast`` from the source folders named in pyproject.toml (so strings, comments and
docstrings that quote a number do not count).
"""
from __future__ import annotations

import ast
import re
import tokenize
import tomllib
from pathlib import Path

import pytest

from swarmdeck.core import constants
from swarmdeck.core.kinematics import GritsBotParams

ROOT = Path(__file__).resolve().parents[2]

#: REFERENCE.md numbers that must appear as a literal only in core/constants.py.
NAMED = {"0.17": "SAFETY_DISTANCE", "0.033": "CONTROL_PERIOD", "0.135": "COLLISION_DISTANCE",
         "12.5": "MAX_WHEEL_SPEED", "0.105": "AXLE_LENGTH", "0.055": "ROBOT_RADIUS",
         "0.11": "ROBOT_DIAMETER"}

#: The same digits that mean something else (file, literal) → what they are; not a REFERENCE.md number.
NOT_REFERENCE = {
    ("console/recording/export_video.py", "0.055"): "the video's header/footer band, a fraction of the frame height",
}
#: Hand-rolled thread lifecycles kept on purpose: the deadline caller's worker is a per-call worker woken by
#: its own condition, never stopped by an event, and its CPU-starvation accounting reads the thread's native_id.
THREADS_LEFT = {"console/runtime/deadline.py"}


def source_files() -> list[Path]:
    dirs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    folders = sorted({ROOT / folder for name, folder in dirs.items() if name.count(".") == 1})
    return [p for folder in folders for p in sorted(folder.rglob("*.py"))]


def rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def test_constants_are_the_reference_values():
    assert constants.SAFETY_DISTANCE == 0.17 and constants.CONTROL_PERIOD == 0.033
    assert constants.ROBOT_RADIUS == 0.055 == GritsBotParams().radius
    p = GritsBotParams()
    assert (p.wheel_radius, p.axle_length, p.max_wheel_speed, p.diameter, p.max_speed, p.lookahead) == (
        constants.WHEEL_RADIUS, constants.AXLE_LENGTH, constants.MAX_WHEEL_SPEED, constants.ROBOT_DIAMETER,
        constants.MAX_LINEAR_SPEED, constants.LOOKAHEAD)
    assert p.max_linear_speed == pytest.approx(constants.MAX_LINEAR_SPEED)


def test_reference_numbers_are_named_once():
    found = []
    for path in source_files():
        name = rel(path)
        if name == "core/constants.py":
            continue
        with path.open("rb") as f:
            for tok in tokenize.tokenize(f.readline):
                if tok.type == tokenize.NUMBER and tok.string in NAMED and (name, tok.string) not in NOT_REFERENCE:
                    found.append(f"{name}:{tok.start[0]}: {tok.string} (use core.constants.{NAMED[tok.string]})")
    assert not found, "\n".join(found)


def test_the_robots_motion_is_defined_once():
    defs = []
    for path in source_files():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.FunctionDef) and node.name in ("wrap_angle", "unicycle_step", "lookahead_points"):
                defs.append((node.name, rel(path)))
    assert sorted(defs) == [("lookahead_points", "core/kinematics.py"), ("unicycle_step", "core/kinematics.py"),
                            ("wrap_angle", "core/kinematics.py")]


def test_service_threads_start_through_core_service_thread():
    rolled = []
    for path in source_files():
        name = rel(path)
        if name == "core/service_thread.py" or name in THREADS_LEFT:
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "Thread"
                    and isinstance(node.func.value, ast.Name) and node.func.value.id == "threading"):
                rolled.append(f"{name}:{node.lineno}")
    assert not rolled, "use swarmdeck.core.service_thread.ServiceThread: " + ", ".join(rolled)


def test_tests_take_shared_fixtures_from_conftest():
    fixture_modules = ("portal_fixtures", "mqtt_broker", "jail_fixtures", "script_env_fixtures", "lab_fixtures")
    pattern = re.compile(rf"^from ({'|'.join(fixture_modules)}) import .*# noqa: F401", re.MULTILINE)
    offenders = [rel(p) for p in sorted((ROOT / "tests").rglob("test_*.py")) if pattern.search(p.read_text())]
    assert not offenders, offenders
    conftest = ast.parse((ROOT / "tests" / "conftest.py").read_text())
    plugins = next(ast.literal_eval(n.value) for n in conftest.body if isinstance(n, ast.Assign)
                   and any(isinstance(t, ast.Name) and t.id == "pytest_plugins" for t in n.targets))
    assert set(plugins) == set(fixture_modules) | {"watchdog"}  # watchdog: hooks only (tests/watchdog.py)
