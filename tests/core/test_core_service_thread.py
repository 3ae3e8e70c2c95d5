"""core.service_thread.ServiceThread: one lifecycle for every background service thread
(idempotent start and stop, a stop event, a bounded join, the error that ended it captured and reported)."""
import threading

from swarmdeck.core.service_thread import ServiceThread


def test_start_is_idempotent_and_stop_joins():
    runs = []
    entered = threading.Event()

    def body():
        runs.append(threading.current_thread().name)
        entered.set()
        while not svc.wait(5.0):
            pass

    svc = ServiceThread(body, "test-svc")
    assert not svc.started and not svc.alive
    assert svc.start() is svc
    assert entered.wait(30)
    svc.start()  # already running: no second thread
    assert svc.started and svc.alive
    assert svc.stop() is True
    assert not svc.alive and not svc.started and svc.stopping
    assert runs == ["test-svc"]
    assert svc.error is None


def test_stop_and_close_before_start_and_twice():
    svc = ServiceThread(lambda: None, "never")
    assert svc.stop() is True
    assert svc.close() is True
    assert not svc.started


def test_restart_after_stop_is_a_new_thread():
    idents = []

    def body():
        idents.append(threading.get_ident())
        svc.wait(None)

    svc = ServiceThread(body, "again")
    for _ in range(2):
        svc.start()
        assert svc.stop() is True
    assert len(idents) == 2
    assert not svc.alive


def test_exception_is_captured_and_given_to_on_error():
    seen = []
    boom = RuntimeError("camera fell off")

    def body():
        raise boom

    svc = ServiceThread(body, "boom", on_error=seen.append)
    svc.start()
    assert svc.stop() is True  # joins; the exception does not propagate here
    assert seen == [boom] and svc.error is boom


def test_exception_without_on_error_is_reported_on_stderr(capfd):
    def body():
        raise ValueError("bad datagram")

    svc = ServiceThread(body, "reporter")
    svc.start()
    svc.stop()
    err = capfd.readouterr().err
    assert "service thread 'reporter' failed" in err and "ValueError: bad datagram" in err
    assert isinstance(svc.error, ValueError)


def test_wake_unblocks_a_target_waiting_on_something_else():
    other = threading.Event()
    svc = ServiceThread(lambda: other.wait(), "waker", wake=other.set)
    svc.start()
    assert svc.stop(timeout=30) is True


def test_stop_from_the_service_thread_itself_does_not_deadlock():
    result = []

    def body():
        result.append(svc.stop())

    svc = ServiceThread(body, "self-stop")
    svc.start()
    assert svc.stop(timeout=30) is True
    assert result == [False] and svc.stopping


def test_a_thread_outliving_the_join_stays_started_until_it_ends():
    release = threading.Event()
    runs = []

    def body():
        runs.append(1)
        release.wait()  # ignores the stop event until released

    svc = ServiceThread(body, "stubborn")
    svc.start()
    assert svc.stop(timeout=0.01) is False
    assert svc.started
    svc.start()  # must not start a second thread next to the stuck one
    release.set()
    assert svc.stop(timeout=30) is True
    assert runs == [1] and not svc.started
