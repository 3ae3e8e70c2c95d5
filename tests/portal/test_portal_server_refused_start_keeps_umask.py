"""A `swarmdeck server` that refuses to start (its data folder cannot be opened) exits 2 and leaves the
calling process's umask as it found it: the server's private umask 077 is for a server that runs."""
import os

from swarmdeck.console.cli import main


def test_unopenable_data_folder_exits_2_and_restores_the_umask(tmp_path, capsys):
    data = tmp_path / "lab"
    data.write_text("a file where the data folder should be")
    before = os.umask(0o022)
    try:
        assert main(["server", "--data", str(data), "--port", "0"]) == 2
        now = os.umask(0o022)
    finally:
        os.umask(before)
    assert "cannot open the data folder" in capsys.readouterr().err
    assert now == 0o022, oct(now)
