"""`swarmdeck server` refuses bad options in one line with exit status 2, before opening anything."""
import pytest

from swarmdeck.console.cli import main


@pytest.mark.parametrize("argv,words", [
    (["--port", "70000"], "--port must be in [0, 65535]"),
    (["--robots", "0"], "--robots must be >= 1"),
    (["--robots", "500"], "at most"),
    (["--workers", "0"], "--workers must be >= 1"),
    (["--verify-runs", "0"], "--verify-runs must be >= 1"),
    (["--verify-concurrent", "0"], "--verify-concurrent must be >= 1"),
    (["--max-duration", "-1"], "--max-duration must be > 0"),
    (["--max-upload", "10"], "--max-upload must be at least 1024"),
    (["--grace", "0"], "--grace must be > 0"),
    (["--fast", "--robots-via", "mqtt://127.0.0.1:1883"], "--fast is for the simulated arena"),
    (["--robots-via", "http://x"], "--robots-via"),
    (["--console-port", "-2"], "--console-port must be in"),
    (["--guard-distance", "0.3"], "--guard-distance must be in [0.05, 0.17] m"),
    (["--guard-intervention", "nan"], "--guard-intervention must be in (0, 1]"),
    (["--host", "203.0.113.9", "--port", "0"], "cannot serve on 203.0.113.9"),
    (["--max-jobs", "-1"], "--max-jobs must be >= 0"),
    (["--verify-cpu", "nan"], "--verify-cpu must be >= 0"),
    (["--disk-quota", "-5"], "--disk-quota must be >= 0"),
    (["--retain-days", "0"], "--retain-days must be > 0"),
    (["--max-connections", "1"], "--max-connections must be >= 2"),
    (["--header-timeout", "0"], "--header-timeout must be in (0, 3600]"),
    (["--body-timeout", "inf"], "--body-timeout must be in (0, 3600]"),
    (["--trust-proxy", "proxy.example.org"], "is not an IP address"),
    (["--projector", "70000"], "--projector port must be in [0, 65535]"),
    (["--projector-calibration", "p.json"], "--projector-calibration needs --projector"),
    (["--projector", "0", "--projector-calibration", "/nonexistent/p.json"], "cannot read projector calibration"),
])
def test_bad_options_exit_2_in_one_line(tmp_path, capsys, argv, words):
    assert main(["server", "--data", str(tmp_path / "lab"), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err
