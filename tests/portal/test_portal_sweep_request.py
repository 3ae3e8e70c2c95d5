"""A portal sweep's request and its job kind, without a server or a run: the request's checks (each naming its key),
the CLI's refusals as 422 with the CLI's own messages, and the sweep job's transitions — verifying → done | failed,
cancellable, never in the arena queue or its plan."""
import pytest

from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.submission import Limits
from swarmdeck.console.portal.sweep_job import MAX_RUNS, check_sweep, parse_request
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sweep.campaign import SweepSpec, plan
from swarmdeck.console.sweep.design import DesignError, parse_axis

SCRIPT = b"from swarmdeck.devices import params\np = params(gain=1.0)\ndef experiment(arena):\n    arena.step()\n"
LIMITS = Limits(fleet=6, max_duration=60.0)
BUNDLE = ScriptBundle.from_files({"script.py": SCRIPT}, "script.py")


def request(**over):
    return parse_request({"params": ["gain=0.5,1"], "robots": 2, "duration": 1.0, **over}, LIMITS)


@pytest.mark.parametrize(("over", "key", "words"), [
    ({"robots": 7}, "robots", "between 1 and 6"),
    ({"robots": "2,x"}, "robots", "not a positive whole number"),
    ({"duration": 0}, "duration", "> 0"),
    ({"duration": 61}, "duration", "at most 60"),
    ({"seeds": 0}, "seeds", ">= 1"),
    ({"seeds": True}, "seeds", "integer"),
    ({"design": "lhs"}, "design", "grid or random"),
    ({"params": "gain=1"}, "params", "list of NAME=VALUES"),
    ({"colour": 1}, "colour", "unknown sweep key"),
    ({"no_barrier": "yes"}, "no_barrier", "true or false"),
])
def test_a_bad_request_is_refused_naming_its_key(over, key, words):
    with pytest.raises(BadInput) as exc:
        request(**over)
    assert exc.value.status == 422 and exc.value.field == key and words in exc.value.message, exc.value.message


def test_a_request_reads_back_what_it_stored_and_robot_counts_as_the_cli_takes_them():
    r = request(robots="2,4", seeds=3)
    assert r.counts == (2, 4) and parse_request(r.to_dict(), LIMITS) == r
    with pytest.raises(BadInput, match="needs 'robots'"):
        parse_request({"params": []}, LIMITS)


def cli_message(*params: str, seeds: int = 1) -> str:
    """What ``swarmdeck sweep`` says of these --param values (its own code path: parse_axis, then plan)."""
    try:
        plan(SweepSpec(BUNDLE, tuple(parse_axis(p) for p in params), seeds=seeds, robots=(2,)))
    except DesignError as exc:
        return str(exc)
    raise AssertionError("the CLI accepted it")


@pytest.mark.parametrize(("params", "seeds"), [
    (("speed=1,2",), 1),  # undeclared
    (("gain=1:2:0",), 1),  # an empty range
    (("gain=0:1:100001",), 1),  # too many points
])
def test_the_clis_refusals_are_422_with_the_same_messages(params, seeds):
    with pytest.raises(BadInput) as exc:
        check_sweep(request(params=list(params), seeds=seeds), BUNDLE)
    assert exc.value.status == 422 and exc.value.message == cli_message(*params, seeds=seeds)


def test_a_sweep_larger_than_the_portal_allows_is_refused_naming_the_limit():
    with pytest.raises(BadInput, match=f"at most {MAX_RUNS}"):
        check_sweep(request(params=[f"gain=0:1:{MAX_RUNS + 1}"]), BUNDLE)
    assert len(check_sweep(request(seeds=2), BUNDLE).runs) == 4


@pytest.fixture(scope="module")
def service(tmp_path_factory):
    svc = PortalService(PortalConfig(data=tmp_path_factory.mktemp("sweeps") / "data", limits=LIMITS))
    yield svc
    svc.close()


def submit(service, who: str):
    user = service.accounts.add_user(who, "researcher")[0]
    return user, service.submit_sweep(user, "gain.py", SCRIPT, {"params": ["gain=0.5,1"], "robots": 2,
                                                                "duration": 1.0})


def claim(service, job_id: int):
    job = service.claim_for_verification()
    assert job is not None and job.id == job_id and job.state == "verifying" and job.sweep is not None
    return job


def test_a_sweep_job_ends_done_or_failed_after_its_runs_and_never_enters_the_arena_queue(service):
    _, job = submit(service, "ann")
    assert job.state == "awaiting verification" and job.eta_start is None  # not in the arena's plan
    claim(service, job.id)
    service.finish_sweep(job.id, True, None)
    assert service.store.get(job.id).state == "done" and service.store.get(job.id).ended is not None
    assert service.claim_for_arena() is None
    _, job = submit(service, "ben")
    claim(service, job.id)
    service.finish_sweep(job.id, False, "the sweep could not run: no jail")
    failed = service.store.get(job.id)
    assert failed.state == "failed" and failed.reason == "the sweep could not run: no jail"


def test_a_sweep_job_is_cancellable_and_its_late_end_changes_nothing(service):
    user, job = submit(service, "cat")
    claim(service, job.id)
    assert service.cancel(user, job.id).state == "cancelled" and service.verifying_cancelled(job.id)
    service.finish_sweep(job.id, True, None)  # the runs stopped after the cancel: it stays cancelled
    assert service.store.get(job.id).state == "cancelled"


@pytest.mark.parametrize(("words", "says"), [
    (["--seeds", "3", "--robots", "2", "--duration", "1"], "add --sweep"),
    (["--promote", "min_distance", "--robots", "2", "--duration", "1"], "add --sweep"),
    (["--param", "gain=1,2", "--robots", "2", "--duration", "1"], "one value per parameter here"),
    (["--sweep", "--param", "gain=1", "--duration", "1"], "--robots N"),
    (["--sweep", "--robots", "2", "--param", "robots=2,4", "--duration", "1"], "give the robot counts once"),
])
def test_swarmdeck_submit_refuses_a_sweep_it_cannot_send(words, says, tmp_path, capsys):
    from swarmdeck.console.cli import main

    script = tmp_path / "gain.py"
    script.write_bytes(SCRIPT)
    assert main(["submit", str(script), *words, "--server", "http://127.0.0.1:9", "--token", "t"]) == 2
    assert says in capsys.readouterr().err
