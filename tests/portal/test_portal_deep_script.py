"""A script nested deeper than Python's parser allows (60 kB of unary minus: the parser raises MemoryError, not
SyntaxError) is refused with 422 naming it — a job with parameters, a sweep — and a plain job is rejected by
verification's compile check without a sandbox run; the portal never answers 500 (before: 500 for the first two)."""
import json

from portal_fixtures import manifest

from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.verification import compile_check

DEEP = "x = " + "-" * 60000 + "1\n"


def test_a_script_too_deep_to_parse_is_refused_naming_it(portal):
    with portal.client("alice") as c:
        r = c.post("/api/jobs", files={"script": ("d.py", DEEP)},
                   data={"manifest": json.dumps(manifest(params={"g": 1}))})
        assert r.status_code == 422 and r.json()["field"] == "script" and "deeper" in r.json()["error"], r.text
        r = c.post("/api/sweeps", files={"script": ("d.py", DEEP)},
                   data={"sweep": json.dumps({"params": ["g=1,2"], "robots": 2, "duration": 1.0})})
        assert r.status_code == 422 and "deeper than Python's parser allows" in r.json()["error"], r.text
        assert c.get("/api/jobs").json() == []
    why = compile_check(ScriptBundle.from_files({"d.py": DEEP.encode()}, "d.py"))
    assert why is not None and "nothing was run" in why
