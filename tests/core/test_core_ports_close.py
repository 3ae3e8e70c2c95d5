"""core.ports.close_ports: the sink first, the source once, even when the sink's close fails."""
import pytest

from swarmdeck.core.ports import close_ports


class Port:
    def __init__(self, log, name, fail=False):
        self.log, self.name, self.fail = log, name, fail

    def close(self):
        self.log.append(self.name)
        if self.fail:
            raise RuntimeError(f"{self.name} failed")


def test_sink_then_source():
    log = []
    close_ports(Port(log, "source"), Port(log, "sink"))
    assert log == ["sink", "source"]


def test_one_object_closed_once():
    log = []
    both = Port(log, "both")
    close_ports(both, both)
    assert log == ["both"]


def test_source_closed_when_the_sink_fails():
    log = []
    with pytest.raises(RuntimeError, match="sink failed"):
        close_ports(Port(log, "source"), Port(log, "sink", fail=True))
    assert log == ["sink", "source"]


def test_source_without_close():
    log = []
    close_ports(object(), Port(log, "sink"))
    assert log == ["sink"]
