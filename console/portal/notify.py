"""Notifications: a researcher is told when their job is verified, starts, ends or is rejected — by a webhook of
their own (an HTTP POST of the event as JSON) and by e-mail through the lab's SMTP server
(``swarmdeck server --smtp HOST:PORT --smtp-from ADDR``).

Off the queue's path: the service only writes each notification to the database's outbox in the transaction of
the change it reports (:meth:`.service.PortalService._event`); :class:`Notifier`, a thread of its own, sends what
is due. A webhook that hangs is cut off after ``timeout_s``; one that fails (no answer, a non-2xx status) or an
SMTP server that refuses is tried again with exponential backoff (``backoff_s`` · 2^attempt, at most
``max_backoff_s``) up to ``max_attempts`` times, then given up (the outbox keeps the error; the researcher's
``GET /api/me/notifications`` shows it). Nothing a receiver does reaches the queue, the claims or the arenas.

The webhook's body: ``{"event": "verified"|"rejected"|"started"|"ended", "job", "name", "owner", "state",
"reason", "arena", "time"}`` (``Content-Type: application/json``; ``User-Agent: swarmdeck-portal``).
"""
from __future__ import annotations

import json
import re
import smtplib
import sqlite3
import time
import urllib.error
import urllib.request
from dataclasses import dataclass
from email.message import EmailMessage

from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.labstore import LabStore, Notice
from swarmdeck.core.service_thread import ServiceThread

EMAIL_RE = re.compile(r"^[^@\s<>,;]{1,64}@[A-Za-z0-9.-]{1,253}\.[A-Za-z]{2,63}$|^[^@\s<>,;]{1,64}@localhost$")


@dataclass(frozen=True)
class SmtpSettings:
    """The lab's SMTP server (plain SMTP; STARTTLS when ``starttls``), the sender address, optional login."""

    host: str
    port: int = 25
    sender: str = "swarmdeck@localhost"
    starttls: bool = False
    username: str | None = None
    password: str | None = None


def parse_smtp(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (or ``HOST``: port 25) -> (host, port); ValueError naming what is wrong."""
    host, sep, port = str(text).rpartition(":")
    if not sep:
        host, port = str(text), "25"
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--smtp {text!r}: write HOST:PORT, e.g. 127.0.0.1:25")
    return host.strip("[]"), int(port)


def check_webhook(url: object) -> str:
    """A webhook URL (http:// or https://, at most 2000 characters); :class:`~.errors.BadInput` otherwise."""
    if not isinstance(url, str) or len(url) > 2000 or not re.match(r"^https?://[^\s/?#]+", url) or any(
            c in url for c in "\r\n\t "):
        raise BadInput(f"webhook must be an http:// or https:// URL, got {str(url)[:100]!r}", "webhook")
    return url


def check_email(address: object) -> str:
    """An e-mail address (one, no display name); :class:`~.errors.BadInput` otherwise."""
    if not isinstance(address, str) or not EMAIL_RE.match(address):
        raise BadInput(f"email must be one address like name@example.org, got {str(address)[:100]!r}", "email")
    return address


def subject(body: dict[str, object]) -> str:
    """The e-mail's subject: ``swarmdeck: job 12 "formation" ended (done)``."""
    what = {"verified": "was verified", "rejected": "was rejected", "started": "started"}.get(str(body["event"]),
                                                                                             "ended")
    state = "" if body["event"] in ("verified", "started") else f" ({body['state']})"
    return f"swarmdeck: job {body['job']} \"{body['name']}\" {what}{state}"


class Notifier:
    """The thread that sends the outbox (module docstring): :meth:`start`, :meth:`stop`; :meth:`send_due` once."""

    def __init__(self, lab: LabStore, smtp: SmtpSettings | None, *, timeout_s: float = 5.0, backoff_s: float = 2.0,
                 max_backoff_s: float = 600.0, max_attempts: int = 8, poll_s: float = 0.5) -> None:
        self.lab, self.smtp = lab, smtp
        self.timeout_s, self.backoff_s, self.max_backoff_s = float(timeout_s), float(backoff_s), float(max_backoff_s)
        self.max_attempts, self.poll_s = int(max_attempts), float(poll_s)
        self.sent = 0
        self.failures = 0
        self._thread = ServiceThread(self._run, "swarmdeck-portal-notify", join_timeout=timeout_s + 5.0)

    def start(self) -> Notifier:
        self._thread.start()
        return self

    def stop(self, timeout: float = 10.0) -> None:
        self._thread.stop(timeout)

    def _run(self) -> None:
        while not self._thread.stopping:
            try:
                self.send_due()
            except sqlite3.Error:
                self.failures += 1  # the database is busy or closing: try again next round
            self._thread.wait(self.poll_s)

    def send_due(self, now: float | None = None) -> int:
        """Send every notification due now; how many went out."""
        went = 0
        for notice in self.lab.due(time.time() if now is None else now):
            if self._thread.stopping:
                break
            try:
                self._send(notice)
            except Exception as exc:  # noqa: BLE001 - a receiver's failure of any kind is retried, never raised
                self.failures += 1
                attempt = notice.attempts + 1
                again = None if attempt >= self.max_attempts else time.time() + min(
                    self.max_backoff_s, self.backoff_s * 2 ** notice.attempts)
                self.lab.mark_failed(notice.id, f"{type(exc).__name__}: {exc}", again, time.time())
            else:
                self.sent += 1
                went += 1
                self.lab.mark_sent(notice.id, time.time())
        return went

    def _send(self, notice: Notice) -> None:
        if notice.channel == "webhook":
            request = urllib.request.Request(notice.target, data=notice.body.encode(), method="POST",
                                             headers={"Content-Type": "application/json",
                                                      "User-Agent": "swarmdeck-portal"})
            with urllib.request.urlopen(request, timeout=self.timeout_s) as answer:  # noqa: S310 - http(s) only
                if not 200 <= answer.status < 300:
                    raise urllib.error.HTTPError(notice.target, answer.status, "not 2xx", answer.headers, None)
            return
        if self.smtp is None:
            raise RuntimeError("no SMTP server is configured (swarmdeck server --smtp HOST:PORT)")
        body = json.loads(notice.body)
        msg = EmailMessage()
        msg["From"], msg["To"], msg["Subject"] = self.smtp.sender, notice.target, subject(body)
        lines = [f"{k}: {body[k]}" for k in ("job", "name", "state", "reason", "arena") if body.get(k) is not None]
        msg.set_content("\n".join([subject(body), "", *lines]) + "\n")
        with smtplib.SMTP(self.smtp.host, self.smtp.port, timeout=self.timeout_s) as smtp:
            if self.smtp.starttls:
                smtp.starttls()
            if self.smtp.username is not None:
                smtp.login(self.smtp.username, self.smtp.password or "")
            smtp.send_message(msg)
