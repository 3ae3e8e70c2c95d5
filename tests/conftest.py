"""Shared pytest fixtures for swarmdeck's suites, and the hypothesis profiles.

Hypothesis profiles: ``ci`` (loaded when the ``CI`` environment variable is set,
or with ``HYPOTHESIS_PROFILE=ci``) is deterministic — derandomized example
generation, no example database (nothing carried between runs or machines), no
deadline (the shared CI cores make timings noisy). ``dev`` (the default) searches
randomly and keeps the local database so a failure found once is replayed first.
"""
from __future__ import annotations

import os

# As `swarmdeck` itself does (console/cli/__init__.py): one BLAS thread. The filter's and the
# coverage code's matrices are small, and threaded BLAS on a busy 2-core machine spin-waits:
# measured 22 s vs 1.2 s CPU for 150 filter ticks at N = 50. Set before numpy loads
# (xdist workers inherit the environment).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

# The shared fixtures, registered once for every test module (the modules stay beside the tests;
# a test imports only the helpers it calls by name): ``portal``, ``mosquitto``, ``jail_run``, ``env``.
pytest_plugins = ("portal_fixtures", "mqtt_broker", "jail_fixtures", "script_env_fixtures", "lab_fixtures")

settings.register_profile("ci", derandomize=True, database=None, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)


def hypothesis_profile(environ: dict) -> str:
    """The profile for an environment: ``HYPOTHESIS_PROFILE`` if set, else ``ci``
    when ``CI`` is set (to anything but "", "0" or "false"), else ``dev``."""
    explicit = environ.get("HYPOTHESIS_PROFILE")
    if explicit:
        return explicit
    ci = environ.get("CI", "").strip().lower()
    return "ci" if ci not in ("", "0", "false", "no") else "dev"


settings.load_profile(hypothesis_profile(os.environ))


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator so that every random scene is reproducible."""
    return np.random.default_rng(12345)
