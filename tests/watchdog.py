"""A hard bound on every test, set-up and teardown included, that nothing can outlast.

pytest-timeout (``timeout`` in pyproject.toml, or a test's ``timeout`` mark) raises inside the
test when its time is up; but a test stuck in C code never sees that exception, and a test whose
cleanup waits without a bound (a thread join, a process wait) hangs again *after* it. One such
test used to hold a CI run until the job's own 90-minute limit, with nothing naming it.

This plugin arms :func:`faulthandler.dump_traceback_later` (a C watchdog thread: it fires whatever
the interpreter is doing) for each test's whole protocol, ``GRACE_S`` after the test's own
timeout. When it fires, every thread's stack is written to ``HUNG_DIR`` in the root folder and
the worker process exits; pytest-xdist then reports the test as failed ("worker crashed while
running …"), starts a fresh worker, and the run goes on. The controller prints the stacks in its
summary.
"""
from __future__ import annotations

import faulthandler
import os
from collections.abc import Generator
from pathlib import Path
from typing import IO

import pytest

#: Seconds past a test's own timeout before its worker is ended (``SWARMDECK_TEST_GRACE_S``
#: overrides it, for the watchdog's own test).
GRACE_S = 120.0
#: Where a hung worker writes its threads' stacks, relative to the root folder.
HUNG_DIR = "test-artifacts/hung"


def grace_s() -> float:
    """:data:`GRACE_S`, or ``SWARMDECK_TEST_GRACE_S`` when set."""
    return float(os.environ.get("SWARMDECK_TEST_GRACE_S", GRACE_S))


def hard_limit_s(item: pytest.Item, default_timeout_s: float) -> float:
    """The seconds after which a test is considered hung: its timeout (mark, else the ini
    value) plus :func:`grace_s`; with no timeout at all, 900 s."""
    mark = item.get_closest_marker("timeout")
    timeout = default_timeout_s
    if mark is not None:
        given = mark.kwargs.get("timeout", mark.args[0] if mark.args else None)
        if given is not None:
            timeout = float(given)
    if timeout <= 0:
        return 900.0
    return timeout + grace_s()


def _hung_dir(config: pytest.Config) -> Path:
    return Path(config.rootpath) / HUNG_DIR


def _ini_timeout(config: pytest.Config) -> float:
    try:
        value = config.getini("timeout")
    except ValueError:  # pytest-timeout not installed
        return 0.0
    return float(value or 0.0)


def pytest_sessionstart(session: pytest.Session) -> None:
    """The controller (or a plain run) clears the stacks of an earlier run."""
    if hasattr(session.config, "workerinput"):
        return
    folder = _hung_dir(session.config)
    if folder.is_dir():
        for stale in folder.glob("*.txt"):
            stale.unlink()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None, None, None]:
    folder = _hung_dir(item.config)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{os.getpid()}.txt"
    handle: IO[str] = open(path, "w", encoding="utf-8")  # noqa: SIM115 - must outlive this frame
    limit = hard_limit_s(item, _ini_timeout(item.config))
    handle.write(f"hung: {item.nodeid} (its worker was ended after {limit:.0f} s)\n")
    handle.flush()
    faulthandler.dump_traceback_later(limit, exit=True, file=handle)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        handle.close()
        path.unlink(missing_ok=True)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Print the stacks any hung worker left (controller, or a plain run)."""
    if hasattr(terminalreporter.config, "workerinput"):
        return
    folder = _hung_dir(terminalreporter.config)
    stacks = sorted(folder.glob("*.txt")) if folder.is_dir() else []
    for path in stacks:
        text = path.read_text(encoding="utf-8", errors="replace")
        if not text.strip():
            continue
        terminalreporter.section(f"hung test ({path.name})", sep="=")
        terminalreporter.write(text + "\n")
