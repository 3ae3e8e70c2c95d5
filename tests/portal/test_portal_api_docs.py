"""The API page (/docs) works on a lab network without Internet: Swagger UI is served by the portal itself (every
script, stylesheet and icon the page names is on the portal's own origin, and served), with no inline script, under
a Content-Security-Policy that allows only this origin; /openapi.json documents the API."""
from html.parser import HTMLParser


class Refs(HTMLParser):
    """Every src/href of the page's script, link, img, iframe; and whether a script has inline code."""

    def __init__(self) -> None:
        super().__init__()
        self.refs: list[str] = []
        self.inline_script = False
        self._in_script = False

    def handle_starttag(self, tag, attrs):  # noqa: ANN001, ANN201
        a = dict(attrs)
        if tag in ("script", "img", "iframe") and a.get("src"):
            self.refs.append(a["src"])
        if tag == "link" and a.get("href"):
            self.refs.append(a["href"])
        self._in_script = tag == "script"

    def handle_endtag(self, tag):  # noqa: ANN001, ANN201
        self._in_script = False

    def handle_data(self, data):  # noqa: ANN001, ANN201
        if self._in_script and data.strip():
            self.inline_script = True


def test_docs_names_only_this_origin_and_serves_what_it_names(portal):
    with portal.client(None) as c:
        r = c.get("/docs")
        assert r.status_code == 200
        csp = r.headers["content-security-policy"]
        assert "script-src 'self'" in csp and "default-src 'self'" in csp and "unsafe-inline" not in csp
        page = Refs()
        page.feed(r.text)
        assert page.refs and not page.inline_script
        for ref in page.refs:
            assert ref.startswith("/") and not ref.startswith("//"), ref  # same origin: no host, no scheme
            asset = c.get(ref)
            assert asset.status_code == 200 and len(asset.content) > 0, ref
        assert {"/docs/assets/swagger-ui-bundle.js", "/docs/assets/swagger-ui.css", "/static/docs.js"} <= set(page.refs)
        assert c.get("/docs/assets/..%2Fcore.py").status_code == 404
        assert c.get("/docs/assets/redoc.standalone.js").status_code == 404  # only what the page needs
        spec = c.get("/openapi.json").json()
    assert "/api/jobs/{job_id}" in spec["paths"]
