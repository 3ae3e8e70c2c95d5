"""``swarmdeck users add|list|disable|enable|token|tokens|revoke``: the lab's accounts and their access tokens
(in the server's data folder)."""
from __future__ import annotations

import argparse
import json
import re
import sys
import time

from swarmdeck.console.cli import UsageError

NAME = "users"
HELP = ("manage the remote-access accounts: add NAME --role researcher|operator (prints its token once), list, "
        "disable, token NAME --expires 30d, tokens NAME, revoke TOKEN-ID")
ORDER = 71
UNITS = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0, "w": 7 * 86400.0}
LIFETIME_RE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([smhdw])\s*$")


def lifetime(text: str | None) -> float | None:
    """``30d``, ``12h``, ``90m``, ``2w``, ``45s`` → seconds (None stays None); :class:`UsageError` otherwise."""
    if text is None:
        return None
    match = LIFETIME_RE.match(text)
    if match is None or not float(match.group(1)) > 0:
        raise UsageError(f"--expires: a lifetime is a positive number and a unit s, m, h, d or w (e.g. 30d), "
                         f"got {text!r}")
    return float(match.group(1)) * UNITS[match.group(2)]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from swarmdeck.console.cli.server import DEFAULT_DATA

    parser.epilog = ("Tokens are stored only as their SHA-256; a token is shown once, when it is made. "
                     "A revoked or expired token is refused (HTTP 401, saying which).")
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    add = sub.add_parser("add", help="add an account and print its access token (shown only once)")
    add.add_argument("name")
    add.add_argument("--role", required=True, choices=("researcher", "operator"))
    lst = sub.add_parser("list", help="list the accounts")
    dis = sub.add_parser("disable", help="disable an account (its tokens and sessions stop working at once)")
    dis.add_argument("name")
    ena = sub.add_parser("enable", help="enable a disabled account again")
    ena.add_argument("name")
    tok = sub.add_parser("token", help="print a new access token for an account (old ones keep working)")
    tok.add_argument("name")
    toks = sub.add_parser("tokens", help="list an account's tokens: id, created, expires, last used, state "
                                         "(never the token itself)")
    toks.add_argument("name")
    rev = sub.add_parser("revoke", help="revoke one token by its id (see `tokens NAME`): it and the web sessions "
                                        "opened with it stop working at once")
    rev.add_argument("token_id", type=int, metavar="TOKEN-ID")
    for p in (add, tok):
        p.add_argument("--expires", default=None, metavar="LIFETIME",
                       help="the token expires after LIFETIME: a number and s, m, h, d or w, e.g. 30d "
                            "(default: never; revoke it with `users revoke`)")
    for p in (lst, toks):
        p.add_argument("--json", action="store_true", help="print one JSON object")
    for p in (parser, add, lst, dis, ena, tok, toks, rev):
        p.add_argument("--data", default=argparse.SUPPRESS if p is not parser else DEFAULT_DATA, metavar="DIR",
                       help=f"the server's data folder (default ./{DEFAULT_DATA})")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.accounts import Accounts, format_time
    from swarmdeck.console.portal.db import Database, SchemaError
    from swarmdeck.console.portal.errors import PortalError

    if not args.action:
        raise UsageError("say what to do: add, list, disable, enable, token, tokens or revoke")
    expires = lifetime(getattr(args, "expires", None))
    try:
        db = Database(args.data)
    except (SchemaError, OSError) as exc:
        raise UsageError(f"cannot open the data folder {args.data!r}: {exc}") from None
    accounts = Accounts(db)
    try:
        if args.action == "add":
            user, token = accounts.add_user(args.name, args.role, expires_in_s=expires)
            until = "" if expires is None else f", valid until {format_time(time.time() + expires)}"
            print(f"added {user.role} {user.name!r}; access token (shown only now, keep it secret{until}):")
            print(token)
        elif args.action == "list":
            users = accounts.users()
            if args.json:
                print(json.dumps({"users": [u.to_dict() for u in users]}))
            else:
                for u in users:
                    print(f"{u.name:24s} {u.role:10s} {'disabled' if u.disabled else 'active'}")
        elif args.action == "disable":
            accounts.disable(args.name)
            print(f"disabled {args.name!r}: its tokens and sessions no longer work")
        elif args.action == "enable":
            accounts.enable(args.name)
            print(f"enabled {args.name!r}")
        elif args.action == "token":
            info, token = accounts.new_token(args.name, expires_in_s=expires)
            print(token)
            print(f"token id {info.id}, expires {format_time(info.expires)} "
                  f"(revoke: swarmdeck users revoke {info.id})", file=sys.stderr)
        elif args.action == "tokens":
            now = time.time()
            infos = accounts.tokens(args.name)
            if args.json:
                print(json.dumps({"tokens": [t.to_dict(now) for t in infos]}))
            else:
                print(f"{'id':>6}  {'created':20s}  {'expires':20s}  {'last used':20s}  state")
                for t in infos:
                    state = t.state(now) + ("" if t.revoked is None else f" {format_time(t.revoked)}")
                    print(f"{t.id:>6}  {format_time(t.created):20s}  {format_time(t.expires):20s}  "
                          f"{format_time(t.last_used):20s}  {state}")
        elif args.action == "revoke":
            info = accounts.revoke(args.token_id)
            print(f"revoked token {info.id} of {info.user!r}: it no longer works")
    except PortalError as exc:
        raise UsageError(exc.message) from None
    finally:
        db.close()
    return 0
