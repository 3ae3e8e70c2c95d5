"""`swarmdeck robots` command line: user mistakes give one clear line and exit code 2."""
from __future__ import annotations

import pytest

from swarmdeck.console.cli import main


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["--robots", "0"], "--robots must be >= 1"),
        (["--robots", "500"], "at most"),
        (["--ids", "5-2"], "is not an id or a range"),
        (["--ids", "1,1"], "names some robot twice"),
        (["--ids", "0-3", "--layout", "2"], "--layout 2 is too small"),
        (["--broker", "http://127.0.0.1:1883"], "scheme 'http' is not supported"),
        (["--pose-rate", "0"], "pose"),
        (["--duration", "-1"], "--duration must be a finite number"),
        (["--trace", "/nonexistent-swarmdeck-dir/trace.txt"], "--trace /nonexistent-swarmdeck-dir/trace.txt: cannot open"),
        (["--broker", "mqtts://127.0.0.1:1", "--ca-certs", "/nonexistent-swarmdeck-ca.pem"], "TLS set-up"),
    ],
)
def test_usage_errors(argv, fragment, capsys):
    assert main(["robots", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("swarmdeck robots: error:") and fragment in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_help_lists_the_broker_options(capsys):
    with pytest.raises(SystemExit):
        main(["robots", "--help"])
    out = capsys.readouterr().out
    for opt in ("--broker", "--robots", "--ids", "--qos", "--mqtt-version", "--ca-certs", "--username", "--timeout"):
        assert opt in out
