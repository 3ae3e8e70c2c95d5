"""The lab's remote-access service (issue 16): accounts, submissions, verification queue, arena runner, results.

* :mod:`.db` — the SQLite database (WAL, versioned schema, the jobs' state machine as conditional updates).
* :mod:`.accounts` — users (researcher | operator), hashed access tokens (expiry, revocation, last use), web
  sessions (CSRF derived by HMAC), sign-in limits, audit log.
* :mod:`.quotas` — per-researcher limits (unfinished jobs, verification CPU a day, disk); :mod:`.retention` — the
  sweep that deletes old results; :mod:`.files` — the data folder's private modes (0700/0600).
* :mod:`.errors` — the errors (status, message, field) and the rejected-request counter.
* :mod:`.submission` — manifest and upload checks (.py, .zip).
* :mod:`.service` — ``PortalService``: every rule (visibility, queue, approval, emergency stop, results).
* :mod:`.workers` — verification workers (local pool or Ray) moving jobs to rejected | approved.
* :mod:`.runner` — the arena runner: one job at a time through the console's ControlLoop, sandboxed script.
* :mod:`.exports` — ``JobExports``: an ended job's CSV, HTML replay and video, in a child process.
* :mod:`.livefeed` — ``LiveFeed``: the running job's newest Frame for the live view.
* :mod:`.api` — the JSON API under /api; :mod:`.app` — ``create_app(service, live=...)``, uvicorn helpers
  (connection limits and timeouts, trusted proxies, the local API docs).
* :mod:`.client` — the HTTP client the ``submit``/``jobs``/``results``/``cancel`` commands use.
"""
