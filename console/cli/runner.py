"""``swarmdeck runner``: an arena on this machine that joins a portal on another (pulls its jobs, pushes results)."""
from __future__ import annotations

import argparse
import os
import sys

from swarmdeck.console.cli import UsageError

NAME = "runner"
HELP = "run one arena of a lab's portal from this machine: pull its jobs over HTTP, push recordings and results"
ORDER = 71


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("The portal declares the arena: `swarmdeck server --arena NAME=remote,robots=N,kind=physical`. "
                     "The token is an operator account's (`swarmdeck users add NAME --role operator`). One runner "
                     "per arena: a second one for the same arena is refused while the first is alive; when a runner "
                     "stops answering, the portal marks its job interrupted (keeping the recording it received) and "
                     "frees the arena.")
    parser.add_argument("--portal", required=True, metavar="URL", help="the portal, e.g. https://arena.example.org")
    parser.add_argument("--arena", required=True, metavar="NAME", help="the arena's name on the portal")
    parser.add_argument("--token", default=None, help="an operator's access token (default: $SWARMDECK_TOKEN)")
    parser.add_argument("--work", default="swarmdeck-runner", metavar="DIR",
                        help="folder for the jobs' files while they run (default ./swarmdeck-runner)")
    parser.add_argument("--robots-via", default=None, metavar="URL",
                        help="drive GRITSBots over MQTT (mqtt://HOST:PORT) instead of simulating them")
    parser.add_argument("--fast", action="store_true", help="simulated robots: as fast as they compute")
    parser.add_argument("--seed", type=int, default=None, help="seed of the simulated arena's start poses")
    parser.add_argument("--trusted", action="store_true",
                        help="run scripts unconfined where this machine cannot confine them")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="run scripts even where no cgroup can be created per run")


def main(args: argparse.Namespace) -> int:
    token = args.token or os.environ.get("SWARMDECK_TOKEN")
    if not token:
        raise UsageError("no access token: --token TOKEN (or set SWARMDECK_TOKEN)")
    if args.fast and args.robots_via:
        raise UsageError("--fast is for simulated robots: networked robots run in real time")
    import signal
    import threading
    from pathlib import Path

    from swarmdeck.console.portal.client import ClientError
    from swarmdeck.console.portal.files import UMASK, private_dir
    from swarmdeck.console.portal.remote_runner import run_remote
    from swarmdeck.console.portal.runner import ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig
    from swarmdeck.console.sandbox.confinement import JailConfig, probe

    reason = probe(JailConfig(allow_no_cgroup=args.allow_no_cgroup))
    if reason is not None and not args.trusted:
        raise UsageError(f"cannot confine untrusted code on this machine: {reason}; install bubblewrap "
                         "or pass --trusted")
    previous_umask = os.umask(UMASK)  # what the runner writes is private; the caller's umask comes back after
    try:
        work = private_dir(Path(args.work))
        config = PortalConfig(data=work, trusted=args.trusted, allow_no_cgroup=args.allow_no_cgroup)
        settings = ArenaSettings(robots_via=args.robots_via, fast=args.fast, seed=args.seed)
        stop = threading.Event()
        saved = {sig: signal.signal(sig, lambda signum, frame: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            return run_remote(args.portal, token, args.arena, work, config, settings, stop,
                              on_connect=lambda spec: print(f"swarmdeck runner: arena {args.arena} of {args.portal}: "
                                                            f"{spec['robots']} {spec['kind']} robots; Ctrl-C to stop",
                                                            flush=True))
        except ClientError as exc:
            print(f"swarmdeck runner: error: {exc.line()}", file=sys.stderr)
            return 1
        finally:
            for sig, handler in saved.items():
                signal.signal(sig, handler)
    finally:
        os.umask(previous_umask)
