"""`swarmdeck users`: add prints the token once (stored only hashed), list, disable/enable, token; one-line errors."""
import json

from swarmdeck.console.cli import main
from swarmdeck.console.portal.accounts import Accounts
from swarmdeck.console.portal.db import Database


def run(capsys, *argv):
    code = main(["users", *argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_add_list_disable_enable_and_token(tmp_path, capsys):
    data = str(tmp_path / "lab")
    code, out, _ = run(capsys, "add", "alice", "--role", "researcher", "--data", data)
    token = out.strip().splitlines()[-1]
    assert code == 0 and token.startswith("sdk_")
    code, out, _ = run(capsys, "list", "--json", "--data", data)
    assert json.loads(out) == {"users": [{"id": 1, "name": "alice", "role": "researcher", "disabled": False}]}
    db = Database(data)
    accounts = Accounts(db)
    assert accounts.user_for_token(token).name == "alice"
    assert run(capsys, "disable", "alice", "--data", data)[0] == 0
    assert accounts.users()[0].disabled
    assert run(capsys, "enable", "alice", "--data", data)[0] == 0
    code, out, _ = run(capsys, "token", "alice", "--data", data)
    assert code == 0 and accounts.user_for_token(out.strip()).name == "alice" != out.strip()
    db.close()


def test_mistakes_are_one_line_and_exit_2(tmp_path, capsys):
    data = str(tmp_path / "lab")
    run(capsys, "add", "alice", "--role", "operator", "--data", data)
    for argv, words in ((("add", "alice", "--role", "operator"), "exists already"),
                        (("add", "a b", "--role", "operator"), "a user name is"),
                        (("disable", "nobody"), "no user called 'nobody'"), ((), "say what to do")):
        code, _, err = run(capsys, *argv, "--data", data)
        assert code == 2 and err.count("\n") == 1 and words in err, err
