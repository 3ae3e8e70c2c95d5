"""The Submit page's Parameters field: a researcher sets the values their script declares with
``swarmdeck.devices.params(...)`` from the browser, as ``swarmdeck submit --param`` does; a malformed line, a range
or an undeclared name comes back on the page naming the field, with the typed text kept."""
from __future__ import annotations

import html
import re

from portal_fixtures import sign_in

DECLARES = ("import numpy as np\n"
            "from swarmdeck.devices import params\n"
            "p = params(gain=1.0, label='a', laps=2)\n"
            "def experiment(arena):\n"
            "    while True:\n"
            "        arena.set_unicycle(np.full(arena.n, 0.02 * p.gain), np.zeros(arena.n))\n"
            "        arena.step()\n")
FIELDS = {"name": "tuned", "robots": "2", "duration": "1"}


def _submit(client, csrf: str, params: str):
    return client.post("/submit", data={"csrf": csrf, **FIELDS, "params": params},
                       files={"script": ("tuned.py", DECLARES.encode())})


def _errors(page: str) -> dict[str, str]:
    return {m.group(1): html.unescape(m.group(2))
            for m in re.finditer(r'<li data-field="([^"]*)">(.*?)</li>', page, re.S)}


def test_the_values_typed_on_the_page_are_the_jobs_parameters(portal):  # noqa: F811
    alice, csrf = sign_in(portal, "alice")
    try:
        r = _submit(alice, csrf, "gain = 2.5\n\nlabel=fast\nlaps = 3\n")
        assert r.status_code == 303, r.text
        job_id = int(r.headers["location"].rsplit("/", 1)[1])
        job = alice.get(f"/api/jobs/{job_id}").json()
        assert job["params"] == {"gain": 2.5, "label": "fast", "laps": 3}, job
        page = alice.get(f"/jobs/{job_id}").text
        assert 'id="params"' in page and "gain=2.5" in page and "laps=3" in page
    finally:
        alice.close()


def test_empty_parameters_leave_the_scripts_defaults(portal):  # noqa: F811
    alice, csrf = sign_in(portal, "alice")
    try:
        r = _submit(alice, csrf, "  \n")
        assert r.status_code == 303, r.text
        job = alice.get(f"/api/jobs/{int(r.headers['location'].rsplit('/', 1)[1])}").json()
        assert job["params"] is None, job
    finally:
        alice.close()


def test_a_bad_line_a_range_or_an_undeclared_name_is_named_on_the_page(portal):  # noqa: F811
    alice, csrf = sign_in(portal, "alice")
    try:
        for typed, says in (("gain 2", "parameters, line 1: 'gain 2' is not name = value"),
                            ("laps = 1\ngain = 1,2", "line 2: 'gain = 1,2': one value per parameter here"),
                            ("gain = 1\ngain = 2", "sets gain a second time"),
                            ("speed = 3", "gain")):
            r = _submit(alice, csrf, typed)
            assert r.status_code == 422, (typed, r.text[:300])
            errors = _errors(r.text)
            assert set(errors) == {"params"}, (typed, errors)
            assert says in errors["params"], (typed, errors["params"])
            assert html.escape(typed.splitlines()[0], quote=False) in r.text  # the typed text is kept
        assert "speed" in errors["params"]  # the undeclared name, beside the declared ones
        assert alice.get("/api/jobs").json() == []  # nothing was queued
    finally:
        alice.close()
