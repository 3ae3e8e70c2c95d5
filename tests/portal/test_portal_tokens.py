"""Access tokens with an expiry, revoked one at a time, with their last use — on real uvicorn and the real CLI:
a revoked token and a token past its expiry get 401 saying which; `swarmdeck users tokens` lists ids and times,
never a secret; revoking a token ends the web sessions opened with it."""
import json
import time

import pytest

from swarmdeck.console.cli import main


def run(capsys, *argv):
    code = main(["users", *argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_a_revoked_token_is_401_saying_revoked_and_the_others_keep_working(portal):
    accounts = portal.service.accounts
    info, second = accounts.new_token("alice")
    with portal.client("alice") as c:
        assert c.get("/api/me").json()["name"] == "alice"
        signed_in = portal.client(None)
        assert signed_in.post("/api/session", json={"token": second}).status_code == 200
        assert signed_in.get("/api/me").status_code == 200
        accounts.revoke(info.id)  # what `swarmdeck users revoke ID` does
        r = c.get("/api/me", headers={"Authorization": f"Bearer {second}"})
        assert r.status_code == 401 and "revoked" in r.json()["error"] and r.json()["field"] == "Authorization"
        assert f"id {info.id}" in r.json()["error"]
        assert signed_in.get("/api/me").status_code == 401  # the session opened with it ended too
        assert c.get("/api/me").json()["name"] == "alice"  # alice's first token still works
        r = c.post("/api/session", json={"token": second})
        assert r.status_code == 401 and "revoked" in r.json()["error"]
        signed_in.close()


def test_a_token_past_its_expiry_is_401_saying_expired(portal):
    accounts = portal.service.accounts
    info, token = accounts.new_token("bob", expires_in_s=3600.0)
    assert info.expires == pytest.approx(time.time() + 3600.0, abs=60)
    with portal.client(None) as c:
        assert c.get("/api/me", headers={"Authorization": f"Bearer {token}"}).json()["name"] == "bob"
        with portal.service.db.transaction() as tx:  # an hour later
            tx.execute("UPDATE tokens SET expires = ? WHERE id = ?", (time.time() - 1.0, info.id))
        r = c.get("/api/me", headers={"Authorization": f"Bearer {token}"})
        assert r.status_code == 401 and "expired" in r.json()["error"], r.text
        r = c.post("/api/session", json={"token": token})
        assert r.status_code == 401 and "expired" in r.json()["error"]


def test_a_session_never_outlives_its_token(portal):
    _, token = portal.service.accounts.new_token("bob", expires_in_s=60.0)
    with portal.client(None) as c:
        body = c.post("/api/session", json={"token": token}).json()
        assert body["expires"] <= time.time() + 61.0


def test_the_cli_makes_lists_and_revokes_tokens_and_never_prints_a_secret(tmp_path, capsys):
    data = str(tmp_path / "lab")
    code, out, _ = run(capsys, "add", "alice", "--role", "researcher", "--expires", "30d", "--data", data)
    first = out.strip().splitlines()[-1]
    assert code == 0 and first.startswith("sdk_") and "valid until" in out
    code, out, err = run(capsys, "token", "alice", "--expires", "12h", "--data", data)
    second = out.strip()
    assert code == 0 and second.startswith("sdk_") and "token id 2" in err and "users revoke 2" in err
    from swarmdeck.console.portal.accounts import Accounts
    from swarmdeck.console.portal.db import Database

    db = Database(data)
    accounts = Accounts(db)
    assert accounts.user_for_token(second).name == "alice"  # used now: last_used is set
    code, out, _ = run(capsys, "tokens", "alice", "--json", "--data", data)
    listed = json.loads(out)["tokens"]
    assert code == 0 and [t["id"] for t in listed] == [1, 2] and first not in out and second not in out
    now = time.time()
    assert listed[0]["expires"] == pytest.approx(now + 30 * 86400, abs=120)
    assert listed[1]["expires"] == pytest.approx(now + 12 * 3600, abs=120)
    assert listed[0]["last_used"] is None and listed[1]["last_used"] == pytest.approx(now, abs=120)
    assert [t["state"] for t in listed] == ["active", "active"]
    code, out, _ = run(capsys, "tokens", "alice", "--data", data)
    assert code == 0 and "last used" in out and "never" in out and "sdk_" not in out
    code, out, _ = run(capsys, "revoke", "2", "--data", data)
    assert code == 0 and "revoked token 2 of 'alice'" in out
    with pytest.raises(Exception, match="revoked on"):
        accounts.user_for_token(second)
    assert accounts.user_for_token(first).name == "alice"
    code, out, _ = run(capsys, "tokens", "alice", "--json", "--data", data)
    assert [t["state"] for t in json.loads(out)["tokens"]] == ["active", "revoked"]
    for argv, words in ((("revoke", "2"), "was revoked already"), (("revoke", "99"), "no token 99"),
                        (("revoke", "99999999999999999999999"), "no token"),
                        (("token", "alice", "--expires", "soon"), "a lifetime is"),
                        (("token", "alice", "--expires", "0d"), "a lifetime is"),
                        (("tokens", "nobody"), "no user called 'nobody'")):
        code, _, err = run(capsys, *argv, "--data", data)
        assert code == 2 and err.count("\n") == 1 and words in err, (argv, err)
    db.close()


def test_last_used_is_written_at_most_once_a_period(portal):
    accounts = portal.service.accounts
    with portal.client("alice") as c:
        for _ in range(5):
            assert c.get("/api/me").status_code == 200
    alice = accounts.tokens("alice")[0]
    assert alice.last_used is not None and alice.last_used <= time.time()
    with portal.client("alice") as c:
        c.get("/api/me")
    assert accounts.tokens("alice")[0].last_used == alice.last_used  # within the period: not rewritten
