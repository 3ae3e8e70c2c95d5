"""``swarmdeck users add|list|disable|enable|token``: the lab's accounts (in the server's data folder)."""
from __future__ import annotations

import argparse
import json

from swarmdeck.console.cli import UsageError

NAME = "users"
HELP = "manage the remote-access accounts: add NAME --role researcher|operator (prints its token once), list, disable"
ORDER = 71


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from swarmdeck.console.cli.server import DEFAULT_DATA

    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    add = sub.add_parser("add", help="add an account and print its access token (shown only once)")
    add.add_argument("name")
    add.add_argument("--role", required=True, choices=("researcher", "operator"))
    lst = sub.add_parser("list", help="list the accounts")
    lst.add_argument("--json", action="store_true", help="print one JSON object")
    dis = sub.add_parser("disable", help="disable an account (its tokens and sessions stop working at once)")
    dis.add_argument("name")
    ena = sub.add_parser("enable", help="enable a disabled account again")
    ena.add_argument("name")
    tok = sub.add_parser("token", help="print a new access token for an account (old ones keep working)")
    tok.add_argument("name")
    for p in (parser, add, lst, dis, ena, tok):
        p.add_argument("--data", default=argparse.SUPPRESS if p is not parser else DEFAULT_DATA, metavar="DIR",
                       help=f"the server's data folder (default ./{DEFAULT_DATA})")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.accounts import Accounts
    from swarmdeck.console.portal.db import Database, SchemaError
    from swarmdeck.console.portal.errors import PortalError

    if not args.action:
        raise UsageError("say what to do: add, list, disable, enable or token")
    try:
        db = Database(args.data)
    except (SchemaError, OSError) as exc:
        raise UsageError(f"cannot open the data folder {args.data!r}: {exc}") from None
    accounts = Accounts(db)
    try:
        if args.action == "add":
            user, token = accounts.add_user(args.name, args.role)
            print(f"added {user.role} {user.name!r}; access token (shown only now, keep it secret):")
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
            print(accounts.new_token(args.name))
    except PortalError as exc:
        raise UsageError(exc.message) from None
    finally:
        db.close()
    return 0
