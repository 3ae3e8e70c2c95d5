"""/openapi.json describes every JSON route's response (a schema, not an empty object) and every operator body,
and what the server answers has that shape: a client generated from the spec can read the portal."""
import jsonschema


def _resolve(spec: dict, schema: dict) -> dict:
    while "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[-1]
        schema = spec["components"]["schemas"][name]
    return schema


def _described(spec: dict, schema: dict) -> bool:
    """A schema that names what is in it: an object with properties, a list of such, or a scalar type
    (``dict[str, Any]`` — an object with no properties — says nothing)."""
    schema = _resolve(spec, schema)
    if "anyOf" in schema:
        return all(_described(spec, s) for s in schema["anyOf"] if s.get("type") != "null")
    if schema.get("type") == "array":
        return _described(spec, schema.get("items", {}))
    if schema.get("type") == "object" or not schema.get("type"):
        return bool(schema.get("properties"))
    return True


def _validator(spec: dict, schema: dict) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator({**schema, "components": spec["components"]})


def test_every_json_route_names_a_response_schema(portal):  # noqa: F811
    with portal.client(None) as c:
        spec = c.get("/openapi.json").json()
    missing, routes = [], 0
    for path, ops in spec["paths"].items():
        for method, op in ops.items():
            for status, response in op["responses"].items():
                if not status.startswith("2"):
                    continue
                content = response.get("content", {})
                if "application/json" not in content:
                    assert "application/octet-stream" in content, (method, path)  # a download: bytes
                    continue
                routes += 1
                if not _described(spec, content["application/json"].get("schema", {})):
                    missing.append(f"{method.upper()} {path}")
    assert routes >= 25 and not missing, missing
    for action, key in (("move", "position"), ("barrier", "forbid"), ("bypass", "approve")):
        body = spec["paths"][f"/api/operator/jobs/{{job_id}}/{action}"]["post"]["requestBody"]
        schema = _resolve(spec, body["content"]["application/json"]["schema"]["anyOf"][0])
        assert key in schema["properties"], action
    job = _resolve(spec, {"$ref": "#/components/schemas/JobOut"})
    assert "awaiting verification" in _resolve(spec, job["properties"]["state"])["enum"]


def test_answers_have_the_shapes_the_spec_names(portal):  # noqa: F811
    jid = portal.submit("alice").json()["id"]
    with portal.client(None) as c:
        spec = c.get("/openapi.json").json()

    def check(client, method: str, path: str, template: str, **kwargs) -> None:
        r = client.request(method, path, **kwargs)
        assert r.status_code < 300, (path, r.text)
        status = str(r.status_code)
        schema = spec["paths"][template][method.lower()]["responses"][status]["content"]["application/json"]["schema"]
        _validator(spec, schema).validate(r.json())

    with portal.client("alice") as alice:
        check(alice, "GET", "/api/me", "/api/me")
        check(alice, "GET", "/api/jobs", "/api/jobs")
        check(alice, "GET", f"/api/jobs/{jid}", "/api/jobs/{job_id}")
        check(alice, "GET", f"/api/jobs/{jid}/files", "/api/jobs/{job_id}/files")
        check(alice, "GET", f"/api/jobs/{jid}/log", "/api/jobs/{job_id}/log")
        check(alice, "GET", "/api/env", "/api/env")
    with portal.client("op1") as op:
        check(op, "POST", f"/api/operator/jobs/{jid}/hold", "/api/operator/jobs/{job_id}/hold")
        check(op, "GET", "/api/operator/arena", "/api/operator/arena")
        check(op, "PUT", "/api/operator/settings", "/api/operator/settings", json={"manual_approval": True})
        check(op, "GET", "/api/operator/audit", "/api/operator/audit")
        check(op, "GET", "/api/operator/stats", "/api/operator/stats")
        check(op, "POST", f"/api/operator/jobs/{jid}/cancel", "/api/operator/jobs/{job_id}/cancel")
