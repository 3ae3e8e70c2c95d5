"""`swarmdeck server --verify-falsify-budget N` reaches every job's verification: the falsifier's budget in its
config, its worst case kept as the job's ``worst-case.mcap`` result file (the search itself is tested jailed in
tests/sandbox/test_sandbox_verify_falsify.py)."""
from __future__ import annotations

from types import SimpleNamespace

from swarmdeck.console.cli import main
from swarmdeck.console.portal.jobfiles import RESULT_FILES, WORST_CASE
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.executors import SerialExecutor


def test_the_portals_falsify_budget_reaches_each_jobs_verification(tmp_path):
    service = PortalService(PortalConfig(data=tmp_path / "data", verify_falsify_budget=30))
    try:
        job = SimpleNamespace(id=3, robots=2, duration=2.0, initial_poses=None, needs="either", arena=None)
        config = VerificationWorkers(service, SerialExecutor()).config_for(job)  # type: ignore[arg-type]
    finally:
        service.close()
    assert config.falsify_budget == 30 and config.to_dict()["falsify_budget"] == 30
    assert WORST_CASE == "worst-case.mcap" and "falsifier" in RESULT_FILES[WORST_CASE]


def test_server_refuses_a_negative_falsify_budget(tmp_path, capsys):
    assert main(["server", "--data", str(tmp_path / "data"), "--port", "0", "--verify-falsify-budget", "-2"]) == 2
    assert "--verify-falsify-budget must be >= 0, got -2" in capsys.readouterr().err
