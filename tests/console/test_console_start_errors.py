"""`swarmdeck console` start-up mistakes: one line and exit 2, or a clear line and a working console
(issue 14, item 17). Only local binds are attempted: nothing is sent off this machine."""
from __future__ import annotations

import socket

import pytest

from swarmdeck.console.cli import main


def _machine_has(address: str) -> bool:
    with socket.socket() as s:
        try:
            s.bind((address, 0))
        except OSError:
            return False
    return True


def test_a_host_this_machine_does_not_have_is_one_line_and_exit_2(capsys) -> None:
    if _machine_has("10.99.99.99"):  # pragma: no cover - a machine configured with that address
        pytest.fail("this test needs a machine without the address 10.99.99.99")
    rc = main(["console", "--host", "10.99.99.99", "--port", "0", "--duration", "0.2", "--no-inputs", "--no-record"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert err == ["swarmdeck console: error: --host 10.99.99.99: not an address of this machine "
                   "(use 127.0.0.1, 0.0.0.0 or one of this machine's addresses)"]


def test_an_unknown_host_name_is_one_line(capsys) -> None:
    rc = main(["console", "--host", "no-such-host.invalid", "--port", "0", "--no-inputs", "--no-record"])
    err = capsys.readouterr().err
    assert rc == 2 and "--host no-such-host.invalid" in err and "Traceback" not in err


def test_a_camera_that_is_not_there_is_one_line_and_exit_2(capfd) -> None:
    rc = main(["console", "--camera", "97", "--port", "0", "--duration", "0.2", "--no-inputs", "--no-record"])
    err = capfd.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("swarmdeck console: error: camera 97: no camera with that index")


def test_a_busy_port_is_named_with_the_port_used_instead(capsys) -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        rc = main(["console", "--port", str(port), "--duration", "0.3", "--robots", "3", "--no-inputs",
                   "--no-record"])
    captured = capsys.readouterr()
    assert rc == 0
    line = [x for x in captured.err.splitlines() if "is in use" in x]
    assert len(line) == 1 and line[0].startswith(f"swarmdeck console: port {port} is in use; serving on port ")
    used = int(line[0].rsplit("port ", 1)[1].split()[0])
    assert used != port and f"http://127.0.0.1:{used}" in captured.out
