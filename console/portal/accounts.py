"""Accounts (the paper's screening: accounts are granted by the lab, never self-served), tokens, web sessions.

* **Users**: a unique name and a role, ``researcher`` or ``operator``;
  :meth:`Accounts.disable` takes effect on the very next request (every request
  looks its token or session up again; nothing is cached).
* **Access tokens**: ``secrets.token_urlsafe(32)`` (256 random bits) with the
  prefix ``sdk_``, shown once by :meth:`Accounts.add_user` / :meth:`Accounts.new_token`
  (optionally with an expiry). Only their SHA-256 is stored, and lookups are by
  that hash. Each has an id (:class:`TokenInfo`: created, expires, revoked, last
  used — updated at most once a minute); :meth:`Accounts.revoke` withdraws one
  token (and ends the web sessions opened with it) at once. A revoked or expired
  token is refused (401) with a message saying which, and when. A plain (unsalted, unstretched) hash
  is right here, unlike for passwords: a token has 256 bits of entropy, so
  neither a dictionary nor a brute-force search of the hash can find it, and an
  indexed equality lookup needs a deterministic hash. A stolen database
  therefore gives no usable token.
* **Web sessions** (the pages' cookie sign-in, :meth:`Accounts.sign_in`): a
  random id (``token_urlsafe(32)``) stored as its SHA-256, with an expiry (at
  most the token's) and a per-session CSRF token (:attr:`Session.csrf`) that pages
  put in their forms and the pages' JavaScript sends as ``X-CSRF-Token``. The
  CSRF token is not stored: it is the HMAC-SHA-256 of the session id under a
  random server secret (``settings.session_secret``, made once per data folder),
  so neither the database nor its backups give it (they hold only the session
  id's hash). The cookie the HTTP layer sets
  is HttpOnly and SameSite=Strict (see :mod:`swarmdeck.console.portal.api`).
* **Sign-in rate limiting**: the token is always checked, and a right one always
  signs in. Wrong ones are counted per client address (the real peer, or what a
  trusted proxy says: ``swarmdeck server --trust-proxy``); after ``max_failures``
  within ``window_s`` a wrong token gets
  :class:`~swarmdeck.console.portal.errors.RateLimited` (429) instead of 401, and
  no more failures are stored for that address until old ones leave the window.
* **Audit log**: :meth:`Accounts.audit` records every operator action
  (who, when, what, which job); :meth:`Accounts.audit_log` lists it, newest first.

No token, session id or CSRF token is ever logged or stored in clear.
"""
from __future__ import annotations

import hashlib
import hmac
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


def format_time(t: float | None) -> str:
    """``2026-11-26 09:40 UTC`` (None: ``never``)."""
    return "never" if t is None else time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(t))


@dataclass(frozen=True)
class TokenInfo:
    """An access token as the lab sees it (never its secret): times are Unix s, None for never."""

    id: int
    user: str
    created: float
    expires: float | None
    revoked: float | None
    last_used: float | None

    def state(self, now: float) -> str:
        """``"revoked"``, ``"expired"`` or ``"active"`` at ``now``."""
        if self.revoked is not None:
            return "revoked"
        if self.expires is not None and self.expires <= now:
            return "expired"
        return "active"

    def to_dict(self, now: float) -> dict:
        return {"id": self.id, "user": self.user, "created": self.created, "expires": self.expires,
                "revoked": self.revoked, "last_used": self.last_used, "state": self.state(now)}


def _token_info(row) -> TokenInfo:  # noqa: ANN001 - sqlite3.Row with the user's name as user_name
    return TokenInfo(int(row["id"]), str(row["user_name"]), float(row["created"]),
                     None if row["expires"] is None else float(row["expires"]),
                     None if row["revoked"] is None else float(row["revoked"]),
                     None if row["last_used"] is None else float(row["last_used"]))


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
        session_s: how long a web session lasts, s (never longer than its token).
        max_failures, window_s: sign-in rate limit per client address (failures, s).
        last_used_period_s: a token's ``last_used`` is written at most this often, s (a write per request
            would serialise every reader behind SQLite's one writer).
        clock: wall clock (Unix s); tests pass their own.
    """

    def __init__(self, db: Database, *, session_s: float = 12 * 3600.0, max_failures: int = 5,
                 window_s: float = 60.0, last_used_period_s: float = 60.0,
                 clock: Callable[[], float] = time.time) -> None:
        self.db = db
        self.session_s, self.max_failures, self.window_s = float(session_s), int(max_failures), float(window_s)
        self.last_used_period_s = float(last_used_period_s)
        self.clock = clock
        self._secret = self._session_secret()

    def _session_secret(self) -> bytes:
        """The data folder's random secret for CSRF tokens (made on first use, kept in ``settings``)."""
        with self.db.transaction() as tx:
            tx.execute("INSERT OR IGNORE INTO settings (key, value) VALUES ('session_secret', ?)",
                       (secrets.token_hex(32),))
            return bytes.fromhex(tx.execute("SELECT value FROM settings WHERE key = 'session_secret'").fetchone()[0])

    def csrf_for(self, sid: str) -> str:
        """The CSRF token of session ``sid``: HMAC-SHA-256(server secret, session id), hex."""
        return hmac.new(self._secret, b"csrf\0" + sid.encode("utf-8"), hashlib.sha256).hexdigest()

    # ------------------------------------------------------------------ users and tokens
    def add_user(self, name: str, role: str, *, expires_in_s: float | None = None) -> tuple[User, str]:
        """Create a user and their first access token (valid ``expires_in_s`` s, None: until revoked); returns
        (user, token) — the token is shown only now."""
        if not isinstance(name, str) or not NAME_RE.match(name):
            raise BadInput("a user name is 1-64 letters, digits or _.@- (starting with a letter or digit)", "name")
        if role not in ROLES:
            raise BadInput(f"role must be one of {', '.join(ROLES)}, got {role!r}", "role")
        expires = self._expiry(expires_in_s)
        token = TOKEN_PREFIX + secrets.token_urlsafe(32)
        now = self.clock()
        with self.db.transaction() as tx:
            if tx.execute("SELECT 1 FROM users WHERE name = ?", (name,)).fetchone():
                raise Conflict(f"a user called {name!r} exists already", "name")
            uid = tx.execute("INSERT INTO users (name, role, created) VALUES (?, ?, ?)", (name, role, now)).lastrowid
            tx.execute("INSERT INTO tokens (user_id, hash, created, expires) VALUES (?, ?, ?, ?)",
                       (uid, digest(token), now, expires))
        return User(int(uid or 0), name, role), token

    def _expiry(self, expires_in_s: float | None) -> float | None:
        if expires_in_s is None:
            return None
        if isinstance(expires_in_s, bool) or not isinstance(expires_in_s, (int, float)) or not expires_in_s > 0 \
                or expires_in_s > 100 * 365 * 86400:
            raise BadInput(f"a token's lifetime must be > 0 s and at most 100 years, got {expires_in_s!r}", "expires")
        return self.clock() + float(expires_in_s)

    def new_token(self, name: str, *, expires_in_s: float | None = None) -> tuple[TokenInfo, str]:
        """Another access token for user ``name`` (the old ones keep working), valid ``expires_in_s`` s (None:
        until revoked): (its info, the token — shown only now)."""
        user = self.user_named(name)
        expires = self._expiry(expires_in_s)
        token = TOKEN_PREFIX + secrets.token_urlsafe(32)
        now = self.clock()
        with self.db.transaction() as tx:
            tid = tx.execute("INSERT INTO tokens (user_id, hash, created, expires) VALUES (?, ?, ?, ?)",
                             (user.id, digest(token), now, expires)).lastrowid
        return TokenInfo(int(tid or 0), user.name, now, expires, None, None), token

    def tokens(self, name: str) -> list[TokenInfo]:
        """User ``name``'s tokens, oldest first (ids, times and state; never the secret)."""
        user = self.user_named(name)
        rows = self.db.query("SELECT t.*, u.name AS user_name FROM tokens t JOIN users u ON u.id = t.user_id "
                             "WHERE t.user_id = ? ORDER BY t.id", (user.id,))
        return [_token_info(r) for r in rows]

    def revoke(self, token_id: int) -> TokenInfo:
        """Revoke token ``token_id`` now: it and the web sessions opened with it stop working at their next
        request. :class:`NotFound` for no such token, :class:`Conflict` if it was revoked already."""
        if isinstance(token_id, bool) or not isinstance(token_id, int) or not 1 <= token_id < 2 ** 63:
            raise NotFound(f"no token {token_id}", "token")
        now = self.clock()
        with self.db.transaction() as tx:
            row = tx.execute("SELECT t.*, u.name AS user_name FROM tokens t JOIN users u ON u.id = t.user_id "
                             "WHERE t.id = ?", (token_id,)).fetchone()
            if row is None:
                raise NotFound(f"no token {token_id}", "token")
            if row["revoked"] is not None:
                raise Conflict(f"token {token_id} of {row['user_name']!r} was revoked already, on "
                               f"{format_time(row['revoked'])}", "token")
            tx.execute("UPDATE tokens SET revoked = ? WHERE id = ?", (now, token_id))
            tx.execute("DELETE FROM sessions WHERE token_id = ?", (token_id,))
        return _token_info({**dict(row), "revoked": now})

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
        """The enabled user owning ``token``; :class:`Unauthorized` otherwise (unknown, revoked, expired, or
        the account disabled), the message saying which."""
        return self._check_token(token)[0]

    def _check_token(self, token: str) -> tuple[User, TokenInfo]:
        if not isinstance(token, str) or not token.startswith(TOKEN_PREFIX) or len(token) > 200:
            raise Unauthorized("not a swarmdeck access token", "Authorization")
        row = self.db.query_one("SELECT t.id AS t_id, t.created AS t_created, t.expires AS t_expires, "
                                "t.revoked AS t_revoked, t.last_used AS t_last_used, u.* FROM tokens t "
                                "JOIN users u ON u.id = t.user_id WHERE t.hash = ?", (digest(token),))
        if row is None:
            raise Unauthorized("unknown access token", "Authorization")
        now = self.clock()
        info = TokenInfo(int(row["t_id"]), str(row["name"]), float(row["t_created"]), row["t_expires"],
                         row["t_revoked"], row["t_last_used"])
        if info.revoked is not None:
            raise Unauthorized(f"this access token (id {info.id}) was revoked on {format_time(info.revoked)}: "
                               "ask the lab for a new one", "Authorization")
        if info.expires is not None and info.expires <= now:
            raise Unauthorized(f"this access token (id {info.id}) expired on {format_time(info.expires)}: "
                               "ask the lab for a new one", "Authorization")
        user = _user(row)
        if user.disabled:
            raise Unauthorized(f"the account {user.name!r} is disabled", "Authorization")
        if info.last_used is None or info.last_used < now - self.last_used_period_s:
            with self.db.transaction() as tx:
                tx.execute("UPDATE tokens SET last_used = ? WHERE id = ?", (now, info.id))
        return user, info

    # ------------------------------------------------------------------ web sessions
    def sign_in(self, token: str, client: str) -> Session:
        """A new web session for the owner of ``token`` (a right token always signs in); a wrong one is
        :class:`Unauthorized`, or :class:`RateLimited` once ``client`` (its address) had ``max_failures``
        within the window."""
        now = self.clock()
        try:
            user, info = self._check_token(token)
        except Unauthorized as exc:
            with self.db.transaction() as tx:
                tx.execute("DELETE FROM signin_failures WHERE t < ?", (now - self.window_s,))
                failures = tx.execute("SELECT COUNT(*) FROM signin_failures WHERE client = ?",
                                      (client,)).fetchone()[0]
                if failures < self.max_failures:
                    tx.execute("INSERT INTO signin_failures (client, t) VALUES (?, ?)", (client, now))
            if failures >= self.max_failures:
                raise RateLimited(f"too many failed sign-ins from this address ({failures} in the last "
                                  f"{self.window_s:g} s, the limit is {self.max_failures}): try again in "
                                  f"{self.window_s:g} s", "token") from None
            raise Unauthorized(str(exc), "token") from None
        sid = secrets.token_urlsafe(32)
        expires = now + self.session_s if info.expires is None else min(now + self.session_s, info.expires)
        with self.db.transaction() as tx:
            tx.execute("DELETE FROM sessions WHERE expires < ?", (now,))
            tx.execute("INSERT INTO sessions (hash, user_id, token_id, created, expires) VALUES (?, ?, ?, ?, ?)",
                       (digest(sid), user.id, info.id, now, expires))
        return Session(sid, user, self.csrf_for(sid), expires)

    def session(self, sid: str) -> Session:
        """The live session with cookie value ``sid``; :class:`Unauthorized` if unknown, expired or disabled."""
        if not isinstance(sid, str) or not sid or len(sid) > 200:
            raise Unauthorized("not signed in", "session")
        row = self.db.query_one("SELECT s.expires AS s_expires, u.* FROM sessions s JOIN users u ON u.id = s.user_id "
                                "WHERE s.hash = ?", (digest(sid),))
        if row is None or float(row["s_expires"]) < self.clock():
            raise Unauthorized("not signed in (or the session expired)", "session")
        user = _user(row)
        if user.disabled:
            raise Unauthorized(f"the account {user.name!r} is disabled", "session")
        return Session(sid, user, self.csrf_for(sid), float(row["s_expires"]))

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
