"""The Submit form (issue 26 item 15): every mistake comes back at once, each naming its field; poses are counted
from 1 as the lines are, and overlapping ones are named; the chosen file's name comes back (a page cannot refill a
file input); the entry field picks the script inside a .zip, on the page, in the API and in `swarmdeck submit
--entry`."""
from __future__ import annotations

import html
import io
import json
import re
import subprocess
import zipfile

from portal_fixtures import CLI, SPIN, sign_in

GOOD = {"name": "spin", "robots": "2", "duration": "1"}


def _zip(files: dict[str, str]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, text in files.items():
            z.writestr(name, text)
    return buf.getvalue()


def _errors(page: str) -> dict[str, str]:
    return {m.group(1): html.unescape(m.group(2))
            for m in re.finditer(r'<li data-field="([^"]*)">(.*?)</li>', page, re.S)}


def test_every_mistake_comes_back_at_once_with_the_typed_fields_and_the_chosen_file(portal):  # noqa: F811
    alice, csrf = sign_in(portal, "alice")
    r = alice.post("/submit", data={"csrf": csrf, "name": "", "robots": "99", "duration": "-1",
                                    "initial_poses": "0 0 0\n0.1 0 0"},
                   files={"script": ("my_walk.py", SPIN.encode())})
    assert r.status_code == 422
    errors = _errors(r.text)
    assert set(errors) == {"name", "robots", "duration", "initial_poses"}, errors
    assert "robots must be between 1 and 6" in errors["robots"] and "duration must be > 0" in errors["duration"]
    # counted from 1 like the lines, and the overlapping poses are named
    assert "poses 1 (0.000, 0.000) and 2 (0.100, 0.000) are 0.100 m apart" in errors["initial_poses"]
    assert "numbered from 1" in errors["initial_poses"] and "at least 0.23 m apart" in errors["initial_poses"]
    assert 'id="script-again"' in r.text and "<b>my_walk.py</b>" in r.text  # choose it again, named
    assert 'value="99"' in r.text and "0.1 0 0</textarea>" in r.text  # the typed fields are kept
    r = alice.post("/submit", data={"csrf": csrf, **GOOD})  # no file at all: said, with nothing else wrong
    assert r.status_code == 422 and set(_errors(r.text)) == {"script"}


def test_the_api_names_overlapping_poses_saying_how_they_are_counted(portal):  # noqa: F811
    r = portal.submit("alice", robots=3, initial_poses=[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.1, 0.0, 0.0]])
    assert r.status_code == 422  # the JSON list's own index, said
    assert r.json()["error"].startswith("initial_poses (numbered from 0): poses 1 (1.000, 0.000) and 2 (1.100, 0.000) "
                                        "are 0.100 m apart")


def test_the_entry_field_picks_the_script_inside_a_zip(portal, tmp_path):  # noqa: F811
    archive = _zip({"run_me.py": SPIN, "helper.py": "X = 1\n"})
    alice, csrf = sign_in(portal, "alice")
    page = alice.get("/submit").text
    assert 'id="entry" name="entry"' in page  # the field the page promises exists
    r = alice.post("/submit", data={"csrf": csrf, **GOOD, "entry": "run_me.py"},
                   files={"script": ("exp.zip", archive)})
    assert r.status_code == 303, _errors(r.text)
    jid = int(r.headers["location"].rsplit("/", 1)[1])
    with portal.client("alice") as c:
        assert c.get(f"/api/jobs/{jid}").json()["entry"] == "run_me.py"
    r = alice.post("/submit", data={"csrf": csrf, **GOOD, "entry": "run_me.py"},
                   files={"script": ("spin.py", SPIN.encode())})
    assert r.status_code == 422 and "only for a .zip" in _errors(r.text)["entry"]
    # the CLI: an archive with its own manifest, the entry named on the command line
    path = tmp_path / "exp.zip"
    path.write_bytes(_zip({"run_me.py": SPIN, "manifest.json": json.dumps({"name": "z", "robots": 2, "duration": 1})}))
    out = subprocess.run([*CLI, "submit", str(path), "--entry", "run_me.py", "--json", "--server", portal.url,
                          "--token", portal.tokens["alice"]], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["entry"] == "run_me.py"
