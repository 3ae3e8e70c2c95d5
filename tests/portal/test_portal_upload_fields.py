"""`POST /api/jobs` and `POST /api/sweeps` refuse a multipart form whose fields are not what they must be — no
script file (a manifest sent as a file is not one), no sweep field — with 422 naming the field, storing nothing.
(One file at most: a second file is refused before, with 400.)"""
import json

import pytest
from portal_fixtures import SPIN, manifest

SWEEP = json.dumps({"params": ["gain=1,2"], "robots": 2, "duration": 1.0})


@pytest.mark.parametrize("path,files,data,field,words", [
    ("/api/jobs", {}, {"manifest": json.dumps(manifest())}, "script", "multipart file field 'script'"),
    ("/api/jobs", {"manifest": ("m.json", "{}")}, {}, "script", "multipart file field 'script'"),
    ("/api/sweeps", {}, {"sweep": SWEEP}, "script", "multipart file field 'script'"),
    ("/api/sweeps", {"script": ("s.py", SPIN)}, {}, "sweep", "form field 'sweep' holding JSON text"),
])
def test_a_malformed_upload_form_is_refused_naming_the_field(portal, path, files, data, field, words):
    with portal.client("alice") as c:
        r = c.post(path, files=files or {"unused": ("u.txt", "")}, data=data)
        assert r.status_code == 422 and r.json()["field"] == field and words in r.json()["error"], r.text
        assert c.get("/api/jobs").json() == []
