"""``swarmdeck train SCENARIO``: train a small policy on a shipped scenario and make it an experiment (or submit it).

Trains PPO (Stable-Baselines3, CPU; the ``learn`` extra) on E swarms of the scenario stepped at once
(:func:`swarmdeck.envs.train.train`), then writes the experiment folder ``--out DIR``: ``policy.npz`` (the actor's
weights, :mod:`swarmdeck.envs.policy`) and ``main.py`` (loads it and drives the arena,
:func:`swarmdeck.envs.deploy.experiment_script`), and ``DIR.zip`` beside it — the two files and a ``manifest.json``,
what ``swarmdeck submit DIR.zip`` sends. ``--submit`` sends it to the portal at once.
"""
from __future__ import annotations

import argparse
import json
import sys
import zipfile
from pathlib import Path

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._client import add_client_arguments, client

NAME = "train"
HELP = "train a small policy (PPO) on a shipped learning scenario; write it as an experiment, --submit it to the portal"
ORDER = 71

POLICY_FILE = "policy.npz"
SCRIPT_FILE = "main.py"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from swarmdeck.envs.scenarios import SHIPPED

    parser.epilog = ("Needs the learn extra: pip install 'swarmdeck[learn]' (Stable-Baselines3 and CPU torch). "
                     "Writes DIR/policy.npz, DIR/main.py and DIR.zip; try it with `swarmdeck run DIR/main.py`, "
                     "`swarmdeck run DIR --sandbox`, send it with `swarmdeck submit DIR.zip` (or --submit here). "
                     "Exit status: 0 done, 1 a server error (or with --wait, the job did not end done), 2 usage.")
    parser.add_argument("scenario", choices=sorted(SHIPPED), metavar="SCENARIO",
                        help=f"the shipped scenario to train on: {', '.join(sorted(SHIPPED))}")
    parser.add_argument("--steps", type=int, default=20000, metavar="K",
                        help="agent-steps of training (every robot of every swarm counts one per step; default 20000)")
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="the experiment folder to write (default: policy-SCENARIO)")
    parser.add_argument("--robots", type=int, default=None, metavar="N",
                        help="robots per swarm, and of the experiment (default: the scenario's)")
    parser.add_argument("--envs", type=int, default=8, metavar="E", help="swarms stepped at once in training (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="the training's seed (default 0)")
    parser.add_argument("--duration", type=float, default=20.0, metavar="S",
                        help="seconds the experiment runs on the arena (its manifest; default 20)")
    parser.add_argument("--no-safety", action="store_true",
                        help="train without the distributed barrier (the experiment always runs inside the arena's)")
    parser.add_argument("--submit", action="store_true", help="submit the experiment to the lab's portal when trained")
    parser.add_argument("--wait", action="store_true", help="with --submit: follow the job to its end")
    add_client_arguments(parser)


def write_experiment(policy: object, out: Path, robots: int, duration: float, name: str) -> Path:
    """Write ``out``/policy.npz and ``out``/main.py, and the archive ``out``.zip (with its manifest); returns the
    archive's path."""
    from swarmdeck.envs.deploy import experiment_script
    from swarmdeck.envs.policy import Policy, save_policy

    assert isinstance(policy, Policy)
    out.mkdir(parents=True, exist_ok=True)
    save_policy(policy, out / POLICY_FILE)
    script = experiment_script(policy, robots, duration)
    (out / SCRIPT_FILE).write_text(script, encoding="utf-8")
    archive = out.parent / f"{out.name}.zip"
    manifest = {"name": name, "robots": robots, "duration": duration, "entry": SCRIPT_FILE}
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(SCRIPT_FILE, script)
        z.write(out / POLICY_FILE, POLICY_FILE)
        z.writestr("manifest.json", json.dumps(manifest))
    return archive


def main(args: argparse.Namespace) -> int:
    for flag, value, low in (("--steps", args.steps, 1), ("--envs", args.envs, 1), ("--robots", args.robots, 1)):
        if value is not None and value < low:
            raise UsageError(f"{flag} must be >= {low}, got {value}")
    if not (args.duration > 0 and args.duration < float("inf")):
        raise UsageError(f"--duration must be > 0 s, got {args.duration}")
    if args.wait and not args.submit:
        raise UsageError("--wait follows a submitted job: add --submit")
    if args.submit:
        client(args).close()  # a missing server or token is named before the training, not after it
    try:
        from swarmdeck.envs.train import train
    except ImportError as exc:
        raise UsageError(str(exc)) from None
    out = Path(args.out or f"policy-{args.scenario}")
    say = (lambda line: print(line, file=sys.stderr)) if args.json else print
    try:
        policy = train(args.scenario, steps=args.steps, n_agents=args.robots, n_envs=args.envs, seed=args.seed,
                       safety=not args.no_safety, progress=say)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    robots = int(policy.scenario_args["n_agents"])
    archive = write_experiment(policy, out, robots, args.duration, f"{args.scenario}-policy")
    say(f"wrote {out / POLICY_FILE}, {out / SCRIPT_FILE} and {archive} ({policy.meta['trained'].get('steps')} "
        f"agent-steps); try it: swarmdeck run {out / SCRIPT_FILE}")
    if not args.submit:
        if args.json:
            print(json.dumps({"policy": str(out / POLICY_FILE), "script": str(out / SCRIPT_FILE),
                              "archive": str(archive)}))
        return 0
    from swarmdeck.console.cli.submit import submit_job

    return submit_job(args, archive, None, None, NAME)
