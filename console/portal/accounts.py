"""Accounts (the paper's screening: accounts are granted by the lab, never self-served), tokens, web sessions.

* **Users**: a unique name and a role, ``researcher`` or ``operator``;
  :meth:`Accounts.disable` takes effect on the very next request (every request
  looks its token or session up again; nothing is cached).
* **Access tokens**: ``secrets.token_urlsafe(32)`` (256 random bits) with the
  prefix ``sdk_``, shown once by :meth:`Accounts.add_user`. Only their SHA-256
  is stored, and lookups are by that hash. A plain (unsalted, unstretched) hash
  is right here, unlike for passwords: a token has 256 bits of entropy, so
  neither a dictionary nor a brute-force search of the hash can find it, and an
  indexed equality lookup needs a deterministic hash. A stolen database
  therefore gives no usable token.
* **Web sessions** (the pages' cookie sign-in, :meth:`Accounts.sign_in`): a
  random id (``token_urlsafe(32)``) stored as its SHA-256, with an expiry and a
  per-session CSRF token (:attr:`Session.csrf`) that pages put in their forms and
  the pages' JavaScript sends as ``X-CSRF-Token``. The cookie the HTTP layer sets
  is HttpOnly and SameSite=Strict (see :mod:`swarmdeck.console.portal.api`).
* **Sign-in rate limiting**: at most ``max_failures`` failed sign-ins per
  client (address) within ``window_s``; further attempts get
  :class:`~swarmdeck.console.portal.errors.RateLimited` without checking the token.
* **Audit log**: :meth:`Accounts.audit` records every operator action
  (who, when, what, which job); :meth:`Accounts.audit_log` lists it, newest first.

No token, session id or CSRF token is ever logged or stored in clear.
"""
from __future__ import annotations

import hashlib
import re
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass

from swarmdeck.console.portal.db import Database
from swarmdeck.console.portal.errors import BadInput, Conflict, NotFound, RateLimited, Unauthorized

ROLES = ("researcher", "operator")
TOKEN_PREFIX = "sdk_"
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.@-]{0,63}$")


def digest(secret: str) -> str:
    """SHA-256 hex of a high-entropy secret (token or session id): what the database stores."""
    return hashlib.sha256(secret.encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class User:
    id: int
    name: str
    role: str
    disabled: bool = False

    @property
    def is_operator(self) -> bool:
        return self.role == "operator"

    def to_dict(self) -> dict:
        return {"id": self.id, "name": self.name, "role": self.role, "disabled": self.disabled}


@dataclass(frozen=True)
class Session:
    """A signed-in browser: ``id`` is the cookie's value (only its hash is stored), ``csrf`` the form token."""

    id: str
    user: User
    csrf: str
    expires: float


def _user(row) -> User:  # noqa: ANN001 - sqlite3.Row
    return User(int(row["id"]), str(row["name"]), str(row["role"]), bool(row["disabled"]))


class Accounts:
    """Users, tokens, sessions, sign-in limits and the audit log on the portal's :class:`Database`.

    Args:
        db: the database.
        session_s: how long a web session lasts, s.
        max_failures, window_s: sign-in rate limit per client.
        clock: wall clock (Unix s); tests pass their own.
    """

    def __init__(self, db: Database, *, session_s: float = 12 * 3600.0, max_failures: int = 5,
                 window_s: float = 60.0, clock: Callable[[], float] = time.time) -> None:
        self.db = db
        self.session_s, self.max_failures, self.window_s = float(session_s), int(max_failures), float(window_s)
        self.clock = clock

    # ------------------------------------------------------------------ users and tokens
    def add_user(self, name: str, role: str) -> tuple[User, str]:
        """Create a user and their first access token; returns (user, token) — the token is shown only now."""
        if not isinstance(name, str) or not NAME_RE.match(name):
            raise BadInput("a user name is 1-64 letters, digits or _.@- (starting with a letter or digit)", "name")
        if role not in ROLES:
            raise BadInput(f"role must be one of {', '.join(ROLES)}, got {role!r}", "role")
        token = TOKEN_PREFIX + secrets.token_urlsafe(32)
        now = self.clock()
        with self.db.transaction() as tx:
            if tx.execute("SELECT 1 FROM users WHERE name = ?", (name,)).fetchone():
                raise Conflict(f"a user called {name!r} exists already", "name")
            uid = tx.execute("INSERT INTO users (name, role, created) VALUES (?, ?, ?)", (name, role, now)).lastrowid
            tx.execute("INSERT INTO tokens (user_id, hash, created) VALUES (?, ?, ?)", (uid, digest(token), now))
        return User(int(uid), name, role), token

    def new_token(self, name: str) -> str:
        """Another access token for user ``name`` (the old ones keep working)."""
        user = self.user_named(name)
        token = TOKEN_PREFIX + secrets.token_urlsafe(32)
        with self.db.transaction() as tx:
            tx.execute("INSERT INTO tokens (user_id, hash, created) VALUES (?, ?, ?)",
                       (user.id, digest(token), self.clock()))
        return token

    def users(self) -> list[User]:
        return [_user(r) for r in self.db.query("SELECT * FROM users ORDER BY id")]

    def user_named(self, name: str) -> User:
        row = self.db.query_one("SELECT * FROM users WHERE name = ?", (name,))
        if row is None:
            raise NotFound(f"no user called {name!r}", "name")
        return _user(row)

    def disable(self, name: str) -> User:
        """Disable a user: their tokens and sessions stop working at their next request."""
        user = self.user_named(name)
        with self.db.transaction() as tx:
            tx.execute("UPDATE users SET disabled = 1 WHERE id = ?", (user.id,))
            tx.execute("DELETE FROM sessions WHERE user_id = ?", (user.id,))
        return User(user.id, user.name, user.role, True)

    def enable(self, name: str) -> User:
        user = self.user_named(name)
        with self.db.transaction() as tx:
            tx.execute("UPDATE users SET disabled = 0 WHERE id = ?", (user.id,))
        return User(user.id, user.name, user.role, False)

    def user_for_token(self, token: str) -> User:
        """The enabled user owning ``token``; :class:`Unauthorized` otherwise (unknown or disabled)."""
        if not isinstance(token, str) or not token.startswith(TOKEN_PREFIX) or len(token) > 200:
            raise Unauthorized("not a swarmdeck access token", "Authorization")
        row = self.db.query_one("SELECT u.* FROM tokens t JOIN users u ON u.id = t.user_id WHERE t.hash = ?",
                                (digest(token),))
        if row is None:
            raise Unauthorized("unknown access token", "Authorization")
        user = _user(row)
        if user.disabled:
            raise Unauthorized(f"the account {user.name!r} is disabled", "Authorization")
        return user

    # ------------------------------------------------------------------ web sessions
    def sign_in(self, token: str, client: str) -> Session:
        """A new web session for the owner of ``token``; :class:`RateLimited` after too many failures
        from ``client`` (its address) within the window, :class:`Unauthorized` for a bad token."""
        now = self.clock()
        with self.db.transaction() as tx:
            tx.execute("DELETE FROM signin_failures WHERE t < ?", (now - self.window_s,))
            failures = tx.execute("SELECT COUNT(*) FROM signin_failures WHERE client = ?", (client,)).fetchone()[0]
        if failures >= self.max_failures:
            raise RateLimited(f"too many failed sign-ins from this address: try again in {self.window_s:g} s", "token")
        try:
            user = self.user_for_token(token)
        except Unauthorized as exc:
            with self.db.transaction() as tx:
                tx.execute("INSERT INTO signin_failures (client, t) VALUES (?, ?)", (client, now))
            raise Unauthorized(str(exc), "token") from None
        sid, csrf = secrets.token_urlsafe(32), secrets.token_urlsafe(24)
        expires = now + self.session_s
        with self.db.transaction() as tx:
            tx.execute("DELETE FROM sessions WHERE expires < ?", (now,))
            tx.execute("INSERT INTO sessions (hash, user_id, csrf, created, expires) VALUES (?, ?, ?, ?, ?)",
                       (digest(sid), user.id, csrf, now, expires))
        return Session(sid, user, csrf, expires)

    def session(self, sid: str) -> Session:
        """The live session with cookie value ``sid``; :class:`Unauthorized` if unknown, expired or disabled."""
        if not isinstance(sid, str) or not sid or len(sid) > 200:
            raise Unauthorized("not signed in", "session")
        row = self.db.query_one("SELECT s.csrf, s.expires, u.* FROM sessions s JOIN users u ON u.id = s.user_id "
                                "WHERE s.hash = ?", (digest(sid),))
        if row is None or float(row["expires"]) < self.clock():
            raise Unauthorized("not signed in (or the session expired)", "session")
        user = _user(row)
        if user.disabled:
            raise Unauthorized(f"the account {user.name!r} is disabled", "session")
        return Session(sid, user, str(row["csrf"]), float(row["expires"]))

    def sign_out(self, sid: str) -> None:
        with self.db.transaction() as tx:
            tx.execute("DELETE FROM sessions WHERE hash = ?", (digest(sid),))

    # ------------------------------------------------------------------ audit log
    def audit(self, user: User | None, action: str, job_id: int | None = None, detail: str = "",
              tx=None) -> None:  # noqa: ANN001 - an open transaction, if any
        """Record an operator action (inside ``tx`` when given, so it commits with the change itself)."""
        sql = "INSERT INTO audit (t, user_id, action, job_id, detail) VALUES (?, ?, ?, ?, ?)"
        args = (self.clock(), None if user is None else user.id, action, job_id, detail)
        if tx is not None:
            tx.execute(sql, args)
        else:
            with self.db.transaction() as own:
                own.execute(sql, args)

    def audit_log(self, limit: int = 200) -> list[dict]:
        """The newest ``limit`` entries: ``{"id", "t", "user", "action", "job", "detail"}``."""
        rows = self.db.query("SELECT a.*, u.name AS user_name FROM audit a LEFT JOIN users u ON u.id = a.user_id "
                             "ORDER BY a.id DESC LIMIT ?", (int(limit),))
        return [{"id": r["id"], "t": r["t"], "user": r["user_name"], "action": r["action"], "job": r["job_id"],
                 "detail": r["detail"]} for r in rows]
