"""``swarmdeck capsule RECORDING|JOB -o run.zip``: the one file that reproduces a run.

A recording made by ``swarmdeck run --record``, ``swarmdeck console`` or the portal carries what reproduces it
(script files with their SHA-256, entry point, seed, arguments, configuration, versions:
:mod:`swarmdeck.console.recording.capsule`); this writes it with the recording as a zip
(:mod:`swarmdeck.console.recording.capsule_zip`). A JOB id downloads the portal job's ``capsule.zip`` instead
(``--server``/``--token`` as ``swarmdeck results``). ``swarmdeck run run.zip`` re-executes it.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._client import add_client_arguments, client, fail

NAME = "capsule"
HELP = ("write the capsule of a run (script files with SHA-256, seeds, configuration, versions and the recording) "
        "to one zip that `swarmdeck run run.zip` re-executes bit for bit")
ORDER = 22


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="RECORDING|JOB",
                        help="an MCAP recording (swarmdeck run --record, swarmdeck console, a portal job's "
                             "recording.mcap) or a portal job's id (downloads its capsule.zip)")
    parser.add_argument("-o", "--output", required=True, metavar="ZIP", help="the capsule to write, e.g. run.zip")
    add_client_arguments(parser)


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.capsule_zip import CapsuleError, read_recorded_capsule, write_capsule

    out = Path(args.output)
    if args.source.isdigit() and not Path(args.source).exists():
        from swarmdeck.console.portal.client import ClientError

        with client(args) as c:
            try:
                size = c.download(int(args.source), "capsule.zip", out)
            except ClientError as exc:
                return fail(NAME, exc, args.json)
            except OSError as exc:
                raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from None
        print(json.dumps({"job": int(args.source), "capsule": str(out), "bytes": size}) if args.json
              else f"{out}  ({size} bytes: the capsule of job {args.source}; swarmdeck run {out})")
        return 0
    try:
        recorded = read_recorded_capsule(args.source)
        path = write_capsule(args.source, out, capsule=recorded)
    except CapsuleError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from None
    m = recorded.manifest
    assert m is not None  # write_capsule refuses a recording without one
    if args.json:
        print(json.dumps({"capsule": str(path), "kind": m.kind, "files": m.files, "key": m.key,
                          "swarmdeck": m.swarmdeck}))
    else:
        files = ", ".join(f"{name} ({digest[:12]}…)" for name, digest in m.files.items()) or "no script files"
        print(f"{path}: capsule of a {m.kind} run by swarmdeck {m.swarmdeck}: {files}; run key {m.key[:16]}…\n"
              f"re-execute and compare: swarmdeck run {path}")
    return 0
