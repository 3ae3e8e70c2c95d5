"""A trained policy as a plain file: an ``.npz`` of weights evaluated with numpy (no pickle, no torch).

``swarmdeck train`` writes one (:mod:`swarmdeck.envs.train`); the experiment script it writes beside it loads it
inside the sandbox with :func:`load_policy` and drives the arena with :func:`swarmdeck.envs.deploy.drive`. A policy
file is untrusted input like any upload: :func:`load_policy` reads it with ``allow_pickle=False`` and checks every
array, raising :class:`PolicyError` (a ``ValueError``) that names the file and what is wrong.

The format (version 1), arrays of one ``numpy.savez`` file:

* ``meta`` — a 0-d unicode array holding a JSON object: ``format`` ("swarmdeck-policy"), ``version`` (1),
  ``scenario`` (a name of :data:`swarmdeck.envs.scenarios.SHIPPED`), ``scenario_args`` (its keyword arguments, JSON
  numbers/strings), ``activation`` ("tanh" or "relu"), ``action`` ("velocity", "goal" or "moves"), ``action_low`` and
  ``action_high`` (2 numbers each: the action box, m/s or m; ignored for moves) and ``trained`` (free-form: library,
  algorithm, steps, seed);
* ``w0``, ``b0``, …, ``w{L-1}``, ``b{L-1}`` — a multilayer perceptron: ``h = act(h @ w_i + b_i)`` for every layer
  but the last, which is linear; ``w_i`` (in, out) and ``b_i`` (out,) float32 or float64, finite; ``w0`` takes the
  scenario's observation (D,); the last layer gives 2 numbers (velocity, goal: the action, clipped into the box) or
  5 (moves: logits, the action is their argmax — the deterministic action of the trained stochastic policy).
"""
from __future__ import annotations

import io
import json
import os
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.errors import SwarmdeckError

FORMAT = "swarmdeck-policy"
VERSION = 1
ACTIVATIONS = ("tanh", "relu")
ACTION_KINDS = ("velocity", "goal", "moves")
MAX_LAYERS = 8
MAX_PARAMETERS = 1 << 20  # weights and biases together
MAX_FILE_BYTES = 8 << 20  # a portal bundle's limit (swarmdeck.console.sandbox.bundle.MAX_BYTES)
MAX_INFLATED_BYTES = 8 * MAX_PARAMETERS + (1 << 20)  # float64 parameters, headers and the metadata
_LAYER_KEY = re.compile(r"^[wb](\d+)$")


class PolicyError(ValueError, SwarmdeckError):
    """A policy file that cannot be used; the message names the file and the problem."""


@dataclass(frozen=True)
class Policy:
    """A checked policy (module docstring). layers: ((w (in, out), b (out,)), …) float64, read-only;
    meta: the JSON object of the file."""

    layers: tuple[tuple[NDArray[np.float64], NDArray[np.float64]], ...]
    activation: str
    action: str
    action_low: NDArray[np.float64]
    action_high: NDArray[np.float64]
    scenario: str
    scenario_args: dict[str, Any]
    meta: dict[str, Any]

    @property
    def obs_size(self) -> int:
        """D, the size of one observation."""
        return int(self.layers[0][0].shape[0])

    def act(self, obs: NDArray[np.floating[Any]]) -> NDArray[Any]:
        """Actions of N agents from their observations ``(N, D)``: ``(N, 2)`` floats clipped into the action box
        (velocity m/s, goal m) or ``(N,)`` ints 0…4 (moves)."""
        h = np.asarray(obs, dtype=np.float64)
        if h.ndim != 2 or h.shape[1] != self.obs_size:
            raise ValueError(f"observations must have shape (N, {self.obs_size}), got {h.shape}")
        last = len(self.layers) - 1
        for i, (w, b) in enumerate(self.layers):
            h = h @ w + b
            if i < last:
                h = np.tanh(h) if self.activation == "tanh" else np.maximum(h, 0.0)
        if self.action == "moves":
            return np.argmax(h, axis=1).astype(np.int64)
        return np.clip(h, self.action_low, self.action_high)


def make_policy(layers: list[tuple[np.ndarray, np.ndarray]], *, scenario: str, scenario_args: dict[str, Any],
                action: str, action_low: Any, action_high: Any, activation: str = "tanh",
                trained: dict[str, Any] | None = None) -> Policy:
    """A policy from weights ``[(w (in, out), b (out,)), …]`` and what it was trained on, checked as a file is."""
    arrays: dict[str, np.ndarray] = {}
    for i, (w, b) in enumerate(layers):
        arrays[f"w{i}"], arrays[f"b{i}"] = np.asarray(w), np.asarray(b)
    meta = {"format": FORMAT, "version": VERSION, "scenario": scenario, "scenario_args": dict(scenario_args),
            "activation": activation, "action": action,
            "action_low": [float(x) for x in np.asarray(action_low, dtype=float).reshape(-1)],
            "action_high": [float(x) for x in np.asarray(action_high, dtype=float).reshape(-1)],
            "trained": dict(trained or {})}
    arrays["meta"] = np.array(json.dumps(meta))
    return _checked("the policy", arrays)


def policy_arrays(policy: Policy) -> dict[str, np.ndarray]:
    """The arrays of ``policy``'s file (module docstring; weights as float32)."""
    arrays: dict[str, np.ndarray] = {"meta": np.array(json.dumps(policy.meta))}
    for i, (w, b) in enumerate(policy.layers):
        arrays[f"w{i}"], arrays[f"b{i}"] = w.astype(np.float32), b.astype(np.float32)
    return arrays


def save_policy(policy: Policy, path: str | os.PathLike[str]) -> Path:
    """Write ``policy`` to ``path`` (an ``.npz``, :func:`policy_arrays`); returns the path."""
    out = Path(path)
    with open(out, "wb") as f:  # savez on a file object: no ".npz" appended behind the caller's back
        np.savez(f, **cast(dict[str, Any], policy_arrays(policy)))
    return out


def load_policy(source: str | os.PathLike[str] | bytes) -> Policy:
    """The policy in a file (a path, or the file's bytes); :class:`PolicyError` naming the file and the problem for
    anything but a well-formed policy (module docstring)."""
    if isinstance(source, bytes):
        shown, data = "the policy file", source
    else:
        shown = f"policy file {str(source)!r}"
        try:
            size = os.path.getsize(source)
            if size > MAX_FILE_BYTES:
                raise PolicyError(f"{shown} is {size} bytes, more than the limit of {MAX_FILE_BYTES}")
            with open(source, "rb") as f:
                data = f.read(MAX_FILE_BYTES + 1)
        except OSError as exc:
            raise PolicyError(f"cannot read {shown}: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise PolicyError(f"{shown} is more than {MAX_FILE_BYTES} bytes")
    try:
        if zipfile.is_zipfile(io.BytesIO(data)):  # an .npz: bound what its members inflate to before reading them
            with zipfile.ZipFile(io.BytesIO(data)) as archive:
                inflated = sum(info.file_size for info in archive.infolist())
            if inflated > MAX_INFLATED_BYTES:
                raise PolicyError(f"{shown} inflates to {inflated} bytes, more than the limit of {MAX_INFLATED_BYTES}")
        loaded = np.load(io.BytesIO(data), allow_pickle=False)
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise PolicyError(f"{shown} is a single .npy array, not an .npz of a policy's arrays")
        with loaded as npz:
            names = list(npz.files)
            if len(names) > 2 * MAX_LAYERS + 1:
                raise PolicyError(f"{shown} holds {len(names)} arrays; a policy has at most {2 * MAX_LAYERS + 1}")
            arrays = {name: npz[name] for name in names}
    except PolicyError:
        raise
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, KeyError) as exc:
        # allow_pickle=False: an object array (a pickle) is a ValueError here, never unpickled
        raise PolicyError(f"{shown} is not a numpy .npz of plain arrays: {exc}") from None
    return _checked(shown, arrays)


def _checked(shown: str, arrays: dict[str, np.ndarray]) -> Policy:
    if "meta" not in arrays:
        raise PolicyError(f"{shown} has no 'meta' array (is it a swarmdeck policy? `swarmdeck train` writes them)")
    meta = _meta(shown, arrays["meta"])
    layer_keys = sorted((k for k in arrays if k != "meta"), key=lambda k: (int(k[1:]) if _LAYER_KEY.match(k) else -1, k))
    bad = [k for k in layer_keys if not _LAYER_KEY.match(k)]
    if bad:
        raise PolicyError(f"{shown}: unexpected array {bad[0]!r} (a policy holds meta, w0, b0, w1, b1, …)")
    n_layers = len(layer_keys) // 2
    if n_layers < 1 or set(layer_keys) != {f"{c}{i}" for i in range(n_layers) for c in "wb"}:
        raise PolicyError(f"{shown}: the layers must be w0, b0, …, w{{L-1}}, b{{L-1}} with 1 <= L <= {MAX_LAYERS}, "
                          f"got {sorted(layer_keys)}")
    if n_layers > MAX_LAYERS:
        raise PolicyError(f"{shown} has {n_layers} layers, more than {MAX_LAYERS}")
    layers = []
    total = 0
    width: int | None = None
    for i in range(n_layers):
        w, b = arrays[f"w{i}"], arrays[f"b{i}"]
        for name, a, ndim in ((f"w{i}", w, 2), (f"b{i}", b, 1)):
            if a.dtype not in (np.float32, np.float64):
                raise PolicyError(f"{shown}: {name} must be float32 or float64, got {a.dtype}")
            if a.ndim != ndim or 0 in a.shape:
                raise PolicyError(f"{shown}: {name} must be a non-empty {ndim}-D array, got shape {a.shape}")
            total += a.size
            if total > MAX_PARAMETERS:
                raise PolicyError(f"{shown} has more than {MAX_PARAMETERS} parameters")
            if not np.all(np.isfinite(a)):
                raise PolicyError(f"{shown}: {name} holds NaN or inf")
        if width is not None and w.shape[0] != width:
            raise PolicyError(f"{shown}: w{i} takes {w.shape[0]} inputs but layer {i - 1} gives {width}")
        if b.shape != (w.shape[1],):
            raise PolicyError(f"{shown}: b{i} must have shape ({w.shape[1]},) to match w{i} {w.shape}, got {b.shape}")
        width = int(w.shape[1])
        wf, bf = w.astype(np.float64), b.astype(np.float64)
        wf.setflags(write=False)
        bf.setflags(write=False)
        layers.append((wf, bf))
    want = 5 if meta["action"] == "moves" else 2
    if width != want:
        raise PolicyError(f"{shown}: the last layer gives {width} numbers; a {meta['action']} policy gives {want}")
    low, high = (np.array(meta[k], dtype=np.float64) for k in ("action_low", "action_high"))
    low.setflags(write=False)
    high.setflags(write=False)
    return Policy(tuple(layers), meta["activation"], meta["action"], low, high, meta["scenario"],
                  dict(meta["scenario_args"]), meta)


def _meta(shown: str, raw: np.ndarray) -> dict[str, Any]:
    """The checked JSON object of the ``meta`` array."""
    if raw.shape != () or raw.dtype.kind != "U":
        raise PolicyError(f"{shown}: 'meta' must be a 0-d string array holding JSON, got {raw.dtype} of shape {raw.shape}")
    try:
        meta = json.loads(str(raw))
    except ValueError as exc:
        raise PolicyError(f"{shown}: 'meta' is not valid JSON: {exc}") from None
    if not isinstance(meta, dict):
        raise PolicyError(f"{shown}: 'meta' must hold a JSON object")
    if meta.get("format") != FORMAT:
        raise PolicyError(f"{shown}: 'meta' format is {meta.get('format')!r}, expected {FORMAT!r}")
    if meta.get("version") != VERSION:
        raise PolicyError(f"{shown}: policy format version {meta.get('version')!r} is not supported (this swarmdeck "
                          f"reads version {VERSION})")
    if meta.get("activation") not in ACTIVATIONS:
        raise PolicyError(f"{shown}: activation must be one of {ACTIVATIONS}, got {meta.get('activation')!r}")
    if meta.get("action") not in ACTION_KINDS:
        raise PolicyError(f"{shown}: action must be one of {ACTION_KINDS}, got {meta.get('action')!r}")
    if not isinstance(meta.get("scenario"), str) or not meta["scenario"]:
        raise PolicyError(f"{shown}: 'scenario' must name a shipped scenario, got {meta.get('scenario')!r}")
    args = meta.get("scenario_args", {})
    if not isinstance(args, dict) or not all(isinstance(k, str) and isinstance(v, (int, float, str, bool))
                                             for k, v in args.items()):
        raise PolicyError(f"{shown}: 'scenario_args' must be an object of numbers and strings, got {args!r}")
    for key in ("action_low", "action_high"):
        box = meta.get(key)
        if (not isinstance(box, list) or len(box) != 2
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in box)):
            raise PolicyError(f"{shown}: {key!r} must be a list of 2 finite numbers, got {box!r}")
    if any(lo > hi for lo, hi in zip(meta["action_low"], meta["action_high"])):
        raise PolicyError(f"{shown}: action_low {meta['action_low']} exceeds action_high {meta['action_high']}")
    if not isinstance(meta.get("trained", {}), dict):
        raise PolicyError(f"{shown}: 'trained' must be a JSON object")
    return {**meta, "scenario_args": dict(args), "trained": dict(meta.get("trained", {}))}
