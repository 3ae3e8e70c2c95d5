"""Every bad input of issue 16 against the real API: a 4xx with a JSON body naming the field, counted; the
server keeps serving and the queue stays consistent."""
import io
import json
import socket
import stat
import threading
import zipfile

import pytest
from portal_fixtures import SPIN, make_portal, manifest


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    """One portal for the stateless refusals (each test checks only its own answer)."""
    p = make_portal(tmp_path_factory.mktemp("portal"), fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    yield p
    p.server.stop()
    p.service.close()


def post(portal, who="alice", **kwargs):
    r = portal.submit(who, **kwargs)
    return r.status_code, r.json()


@pytest.mark.parametrize("text,field,words", [
    ("{not json", "manifest", "not valid JSON"),
    ("[1, 2]", "manifest", "must be a JSON object"),
    ('{"robots": 2, "duration": 1}', "name", "needs 'name'"),
    ('{"name": "x", "robots": 2, "duration": 1, "colour": "red"}', "colour", "unknown manifest key"),
    ('{"name": "x", "robots": "two", "duration": 1}', "robots", "must be an integer"),
    ('{"name": "x", "robots": 7, "duration": 1}', "robots", "between 1 and 6"),
    ('{"name": "x", "robots": 0, "duration": 1}', "robots", "between 1 and 6"),
    ('{"name": "x", "robots": 2, "duration": 0}', "duration", "> 0 and at most 60"),
    ('{"name": "x", "robots": 2, "duration": -3}', "duration", "> 0"),
    ('{"name": "x", "robots": 2, "duration": 1e12}', "duration", "at most 60 s"),
    ('{"name": "x", "robots": 2, "duration": NaN}', "duration", "must be a number"),
    ('{"name": "x", "robots": 2, "duration": 1, "no_barrier": "yes"}', "no_barrier", "true or false"),
    ('{"name": "x", "robots": 2, "duration": 1, "initial_poses": [[0, 0, 0]]}', "initial_poses", "1 rows but"),
    ('{"name": "x", "robots": 2, "duration": 1, "initial_poses": [[0, 0, 0], [0.1, 0, 0]]}', "initial_poses",
     "0.23 m apart"),
    ('{"name": "x", "robots": 2, "duration": 1, "initial_poses": [[0, 0, 0], [5, 0, 0]]}', "initial_poses",
     "outside the arena"),
    ('{"name": "x", "robots": 2, "duration": 1, "initial_poses": [[0, 0, "a"], [1, 0, 0]]}', "initial_poses",
     "number triples"),
])
def test_malformed_manifests_are_422_naming_the_key(shared, text, field, words):
    status, body = post(shared, data={"manifest": text})
    assert status == 422 and body["field"] == field and words in body["error"], body


def test_good_initial_poses_are_kept(portal):
    status, body = post(portal, robots=2, initial_poses=[[0, 0, 0], [0.5, 0, 1]])
    assert status == 201 and body["initial_poses"] == [[0.0, 0.0, 0.0], [0.5, 0.0, 1.0]]


def zip_bytes(members, links=()):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for name, data in members.items():
            z.writestr(name, data)
        for name, target in links:
            info = zipfile.ZipInfo(name)
            info.external_attr = (stat.S_IFLNK | 0o777) << 16
            z.writestr(info, target)
    return buf.getvalue()


@pytest.mark.parametrize("members,links,status,words", [
    ({"../evil.py": SPIN}, (), 422, "only plain relative names"),
    ({"/etc/evil.py": SPIN}, (), 422, "only plain relative names"),
    ({"a/../../evil.py": SPIN}, (), 422, "only plain relative names"),
    ({"a\\..\\evil.py": SPIN}, (), 422, "only plain relative names"),
    ({"main.py": SPIN}, (("link.py", "/etc/passwd"),), 422, "'link.py' is a link"),
    ({"main.py": SPIN, "big.bin": b"\0" * (2 << 20)}, (), 413, "more than 1048576"),  # a zip bomb
    ({"data.txt": "x"}, (), 422, "no .py script"),
])
def test_bad_archives_are_refused_and_nothing_is_written(shared, members, links, status, words):
    got, body = post(shared, source=zip_bytes(members, links), filename="job.zip")
    assert got == status and body["field"] == "script" and words in body["error"], body
    assert not list(shared.service.data.parent.rglob("evil.py")) and not list((shared.service.data / "jobs").iterdir())
    assert shared.service.db.query("SELECT * FROM jobs") == []


def test_an_archive_with_several_scripts_needs_its_entry_named(shared):
    data = zip_bytes({"a.py": SPIN, "b.py": "x = 1\n"})
    got, body = post(shared, source=data, filename="job.zip")
    assert got == 422 and body["field"] == "entry" and "name the one to run" in body["error"]
    got, body = post(shared, source=data, filename="job.zip", entry="c.py")
    assert got == 422 and body["field"] == "entry" and "'c.py' is not in the archive" in body["error"]


def test_a_zip_with_its_manifest_inside_is_accepted(portal):
    data = zip_bytes({"main.py": SPIN, "manifest.json": json.dumps(manifest("zipped", robots=3))})
    status, body = post(portal, source=data, filename="job.zip", data={})
    assert status == 201 and body["kind"] == "zip" and body["robots"] == 3 and body["entry"] == "main.py"
    assert (portal.service.job_dir(body["id"]) / "src" / "main.py").read_text() == SPIN


@pytest.mark.parametrize("filename,source,status,words", [
    ("run.sh", b"echo hi\n", 415, ".py) or a .zip"),
    ("noext", b"x = 1\n", 415, ".py) or a .zip"),
    ("bin.py", b"\x00\x01\x02", 422, "not text"),
    ("latin.py", "é = 1\n".encode("latin-1"), 422, "not UTF-8"),
    ("fake.zip", b"PK\x03\x04 not really", 422, "cannot be read as a zip"),
])
def test_wrong_upload_types_are_refused(shared, filename, source, status, words):
    got, body = post(shared, source=source, filename=filename)
    assert got == status and body["field"] == "script" and words in body["error"], body


def test_a_missing_script_field_is_named(portal):
    with portal.client("alice") as c:
        r = c.post("/api/jobs", data={"manifest": json.dumps(manifest())})
        assert r.status_code == 422 and r.json()["field"] == "script"
        r = c.post("/api/jobs", json=manifest())
        assert r.status_code == 422 and r.json()["field"] == "script"


def _read_response(s: socket.socket) -> tuple[bytes, dict]:
    """(status line, JSON body) of one HTTP/1.1 response with a Content-Length."""
    data = b""
    while b"\r\n\r\n" not in data:
        part = s.recv(65536)
        assert part, f"connection closed before a response: {data!r}"
        data += part
    head, body = data.split(b"\r\n\r\n", 1)
    length = int(next(line.split(b":")[1] for line in head.split(b"\r\n") if line.lower().startswith(b"content-length")))
    while len(body) < length:
        body += s.recv(65536)
    return head.split(b"\r\n")[0], json.loads(body[:length])


def _connect(url: str) -> socket.socket:
    host, port = url.split("//")[1].split(":")
    return socket.create_connection((host, int(port)), timeout=30)


def test_an_oversize_upload_is_refused_while_it_streams_and_the_server_keeps_serving(portal):
    token = portal.tokens["alice"]
    limit = portal.service.config.limits.max_upload_bytes
    head = (f"POST /api/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {token}\r\n"
            "Content-Type: multipart/form-data; boundary=BOUNDARY\r\nTransfer-Encoding: chunked\r\n\r\n").encode()
    part = b"--BOUNDARY\r\nContent-Disposition: form-data; name=\"script\"; filename=\"big.py\"\r\n\r\n"
    chunk = b"#" * (64 << 10)
    sent = 0
    with _connect(portal.url) as s:
        s.sendall(head + b"%x\r\n" % len(part) + part + b"\r\n")
        try:  # stream up to 4 MB (the limit is 64 KiB): the server answers once it passed the limit
            while sent < (4 << 20):
                s.sendall(b"%x\r\n" % len(chunk) + chunk + b"\r\n")
                sent += len(chunk)
                if sent > limit + (128 << 10):
                    break  # the answer is due: stop sending and read it
        except (BrokenPipeError, ConnectionResetError):
            pass
        status, body = _read_response(s)
    assert status.startswith(b"HTTP/1.1 413"), status
    assert body["field"] == "script" and "passed the limit" in body["error"]
    # declared too large: refused before a byte of the body is read
    head = (f"POST /api/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {token}\r\n"
            f"Content-Type: multipart/form-data; boundary=B\r\nContent-Length: {1 << 30}\r\n\r\n").encode()
    with _connect(portal.url) as s:
        s.sendall(head)
        status, body = _read_response(s)
    assert status.startswith(b"HTTP/1.1 413") and "1073741824 bytes" in body["error"]
    status, job = post(portal)  # still serving
    assert status == 201 and portal.service.db.check() == "ok"
    with portal.client("op1") as c:
        assert c.get("/api/operator/stats").json()["rejected"]["by_field"]["413 script"] == 2
    assert [j.id for j in portal.service.jobs(portal.service.accounts.user_named("alice"))] == [job["id"]]


def test_two_operators_approving_one_job_at_once_get_one_success_and_one_409(portal):
    svc = portal.service
    op = svc.accounts.user_named("op1")
    svc.set_manual_approval(op, True)
    jid = post(portal)[1]["id"]
    with svc.db.transaction() as tx:  # as a verification worker leaves it
        svc.db.transition(tx, jid, "verifying")
        svc.db.transition(tx, jid, "awaiting approval", verdict="accepted")
    start = threading.Barrier(2)
    results = {}

    def act(who, action):
        with portal.client(who) as c:
            start.wait()
            results[who] = c.post(f"/api/operator/jobs/{jid}/{action}")

    threads = [threading.Thread(target=act, args=("op1", "approve")), threading.Thread(target=act, args=("op2", "approve"))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    codes = sorted(r.status_code for r in results.values())
    assert codes == [200, 409]
    loser = next(r for r in results.values() if r.status_code == 409).json()
    assert loser == {"error": f"job {jid} is already in arena queue", "field": "job"}
    assert svc.job_state(jid) == "in arena queue"
    assert [e["action"] for e in svc.accounts.audit_log()] == ["approve", "manual approval on"]
    # two operators cancelling at once: one cancels, the other is told it already is
    start = threading.Barrier(2)
    threads = [threading.Thread(target=act, args=(who, "cancel")) for who in ("op1", "op2")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(r.status_code for r in results.values()) == [200, 409]
    assert svc.job_state(jid) == "cancelled"
