"""The swarmdeck recording format: MCAP profile, topics and their JSON Schemas.

A recording is an MCAP file (REFERENCE.md §10) with header profile
``"swarmdeck"``, a ``"swarmdeck"`` Metadata record (string map, every value
JSON-encoded: ``recording_format``, ``frame_format``, ``created``, ``robots``,
``bounds``, ``versions``, …) written straight after the header, and JSON
channels (message encoding ``json``, schema encoding ``jsonschema``, so
Foxglove shows them):

==========================  ===============================================
topic                       message
==========================  ===============================================
``/swarmdeck/frame``        one per tick: ``codec.encode_frame`` (format 3: binary per-robot
                            arrays; a keyframe first in every chunk, the others predicted from
                            the frame before them); format-2 files hold self-contained frames
                            only, format-1 files ``Frame.to_dict()``
``/swarmdeck/datagram``     one raw input datagram: ``{t, data (base64), peer, transport, listener}``
``/swarmdeck/config``       the run's configuration and metadata, once at the start
``/swarmdeck/event``        ``{t, kind, text}`` operator actions, frame events, recorder notices
``/swarmdeck/operator``     one typed operator action: ``{tick, time, type, <fields>}``
                            (:mod:`swarmdeck.console.runtime.operator_events`), written before the
                            frame of the tick it took effect in; present when ``config.operator_events``
==========================  ===============================================

Message ``log_time`` is ``start_unix_ns + round((t − time_origin) · 1e9)`` where
``t`` is the console clock of the message (s) and ``time_origin``/``start_unix_ns``
are in the metadata; the exact ``t`` is inside every message.
"""
from __future__ import annotations

from typing import Any

PROFILE = "swarmdeck"
#: Version of the container layout (topics, metadata keys). Readers refuse newer files.
#: 3: frames in frame format 3 (``codec.py``: a keyframe first in every chunk, then frames predicted from the one before);
#: 2: frames in the compact frame format 2; 1: frames as ``Frame.to_dict()`` (both still read).
RECORDING_FORMAT = 3
METADATA_NAME = "swarmdeck"

TOPIC_FRAME = "/swarmdeck/frame"
TOPIC_DATAGRAM = "/swarmdeck/datagram"
TOPIC_CONFIG = "/swarmdeck/config"
TOPIC_EVENT = "/swarmdeck/event"
TOPIC_OPERATOR = "/swarmdeck/operator"
#: ``config.operator_events``: the recording carries every operator action on TOPIC_OPERATOR (version 1).
OPERATOR_EVENTS = 1

_NUM: dict[str, Any] = {"oneOf": [{"type": "number"}, {"enum": ["NaN", "Infinity", "-Infinity"]}]}
_INT: dict[str, Any] = {"type": "integer"}


def _arr(items: dict[str, Any], length: int | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "array", "items": items}
    if length is not None:
        out["minItems"] = out["maxItems"] = length
    return out


_VEC2 = _arr(_NUM, 2)
_MAP_SCALARS = {"type": "object", "additionalProperties": {"type": ["number", "string", "boolean", "null"]}}

FRAME_SCHEMA_V1: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Frame",
    "description": "One control tick of the swarmdeck console (console/runtime/frame.py). Units m, s, rad.",
    "type": "object",
    "required": ["format", "tick", "time", "dt", "bounds", "lookahead", "ids", "poses", "seen",
                 "nominal", "safe", "v", "w", "barrier", "coverage", "density", "contacts",
                 "behaviour", "run_state"],
    "properties": {
        "format": _INT,
        "tick": {"type": "integer", "minimum": 0},
        "time": _NUM, "dt": _NUM, "run_time": _NUM, "lookahead": _NUM,
        "bounds": _arr(_NUM, 4),
        "ids": _arr(_INT),
        "poses": _arr(_arr(_NUM, 3)),
        "seen": _arr({"type": "boolean"}),
        "nominal": _arr(_VEC2), "safe": _arr(_VEC2),
        "v": _arr(_NUM), "w": _arr(_NUM),
        "barrier": {"oneOf": [{"type": "null"}, {
            "type": "object",
            "required": ["enabled", "ok", "status", "active_pairs", "active_h", "intervention"],
            "properties": {
                "enabled": {"type": "boolean"}, "ok": {"type": "boolean"}, "status": {"type": "string"},
                "solve_time_s": _NUM, "n_constraints": _INT, "n_active": _INT,
                "active_pairs": _arr(_arr(_INT, 2)), "active_h": _arr(_NUM),
                "min_distance": _NUM, "min_wall_clearance": _NUM, "intervention": _arr(_NUM),
                "nominal_was_safe": {"type": "boolean"}, "safety_distance": _NUM,
            }}]},
        "coverage": {"oneOf": [{"type": "null"}, {
            "type": "object",
            "required": ["centroids", "masses", "edges", "neighbours", "cost_H", "mean_centroid_distance"],
            "properties": {
                "centroids": _arr(_VEC2), "masses": _arr(_NUM), "edges": _arr(_arr(_VEC2, 2)),
                "neighbours": _arr(_arr(_INT, 2)), "cost_H": _NUM, "mean_centroid_distance": _NUM,
                "packing_warning": {"type": ["string", "null"]},
                "cell_vertices": _arr(_VEC2), "cell_offsets": _arr(_INT),
            }}]},
        "density": {"oneOf": [{"type": "null"}, {
            "type": "object", "required": ["floor", "mu", "weight"],
            "properties": {"floor": _NUM, "mu": _arr(_VEC2), "weight": _arr(_NUM)}}]},
        "contacts": {
            "type": "object", "required": ["sources", "ids", "positions", "velocities"],
            "properties": {"sources": _arr({"type": "string"}), "ids": _arr(_INT),
                           "positions": _arr(_VEC2), "velocities": _arr(_VEC2)}},
        "behaviour": {"type": "string"},
        "run_state": {"enum": ["running", "paused", "estop"]},
        "params": _MAP_SCALARS,
        "events": _arr({"type": "string"}),
        "alerts": _arr({"type": "string"}),
        "health": {"type": "object", "additionalProperties": {"type": "string"}},
        "timing": {"type": "object", "additionalProperties": _NUM},
        "image_ref": {"type": ["string", "null"]},
        "is_virtual": _arr({"type": "boolean"}),
        "battery": _arr(_NUM),
        "charging": _arr({"type": "boolean"}),
        "network": {"type": "object", "required": ["links", "rate"], "description": "the robots' communication "
                    "graph this tick: directed links (sender, receiver) and messages per second over each",
                    "properties": {"links": _arr(_arr(_INT, 2)), "rate": _arr(_NUM)}},
    },
}

_ND: dict[str, Any] = {
    "type": "object", "required": ["nd", "shape", "b64"],
    "description": "binary array: little-endian numpy dtype, shape, base64 of the byte-shuffled bytes "
                   "(all bytes 0 of the elements, then all bytes 1, …)",
    "properties": {"nd": {"enum": ["<f8", "<f4", "<f2", "<i8", "<i4", "<i2", "|b1", "<u8"]}, "shape": _arr({"type": "integer", "minimum": 0}),
                   "b64": {"type": "string", "contentEncoding": "base64"}},
}

FRAME_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Frame",
    "description": "One control tick of the swarmdeck console, frame format 3 (console/recording/codec.py): "
                   "per-robot arrays binary; safe, active_h and the coverage geometry derived "
                   "on reading; with 'pred', ids, poses, v and w are residuals against their prediction from the "
                   "frame of tick pred.ref, the one before it in the chunk (keyframes have no 'pred'). Units m, s, rad.",
    "type": "object",
    # barrier and coverage are left out of a frame that has none (every behaviour but coverage has no
    # coverage state; a reader takes a missing one as null)
    "required": ["format", "tick", "time", "dt", "bounds", "lookahead", "ids", "poses", "seen",
                 "nominal_minus_safe", "v", "w", "density", "contacts", "behaviour", "run_state"],
    "properties": {
        **{k: v for k, v in FRAME_SCHEMA_V1["properties"].items()
           if k not in ("ids", "poses", "seen", "nominal", "safe", "v", "w", "barrier", "coverage")},
        "format": {"const": 3},
        "pred": {"type": "object", "required": ["ref", "crc"],
                 "properties": {"ref": _INT, "crc": {"type": "integer", "minimum": 0}}},
        "ids": _ND, "poses": _ND, "seen": _ND, "nominal_minus_safe": _ND, "v": _ND, "w": _ND,
        "is_virtual": _ND, "battery": _ND, "charging": _ND,
        "network": {"type": "object", "required": ["links", "rate"],
                    "properties": {"links": _ND, "rate": _ND}},
        "barrier": {"oneOf": [{"type": "null"}, {
            "type": "object", "required": ["enabled", "ok", "status", "active_pairs", "intervention", "safety_distance"],
            "properties": {
                "enabled": {"type": "boolean"}, "ok": {"type": "boolean"}, "status": {"type": "string"},
                "solve_time_s": _NUM, "n_constraints": _INT, "n_active": _INT, "active_pairs": _ND,
                "intervention": _ND,
                "min_distance": _NUM, "min_wall_clearance": _NUM, "nominal_was_safe": {"type": "boolean"},
                "safety_distance": _NUM,
            }}]},
        "coverage": {"oneOf": [{"type": "null"}, {
            "type": "object", "required": ["cost_H", "mean_centroid_distance", "geometry"],
            "properties": {
                "cost_H": _NUM, "mean_centroid_distance": _NUM, "packing_warning": {"type": ["string", "null"]},
                "geometry": {"enum": ["derived", "none"]}, "centroids": _ND, "masses": _ND,
                "config": {"type": "object", "description": "the coverage geometry config where it differs from "
                           "the defaults on the frame's bounds (swarmdeck.coverage.GeometryConfig): bounds, "
                           "wall_margin, min_separation (m), quadrature {resolution, reach, max_level, min_level}",
                           "properties": {"bounds": _arr({"type": "number"}, 4), "wall_margin": _NUM,
                                          "min_separation": _NUM, "quadrature": {"type": "object"}}},
            }}]},
    },
}

DATAGRAM_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Datagram",
    "description": "One raw input datagram as received, before parsing (replayed through the real parser).",
    "type": "object",
    "required": ["t", "data", "peer", "transport"],
    "properties": {
        "t": {"type": "number", "description": "receive time, s, console clock"},
        "data": {"type": "string", "contentEncoding": "base64", "description": "the datagram bytes"},
        "peer": {"oneOf": [{"type": "string"}, {"type": "array", "items": {"type": ["string", "integer"]}}],
                 "description": "sender: [host, port] or a name"},
        "transport": {"type": "string", "description": "udp | tcp | …"},
        "listener": {"type": ["string", "null"], "description": "name of the receiving listener, if known"},
    },
}

CONFIG_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Config",
    "description": "Configuration and metadata of the recorded run.",
    "type": "object",
    "required": ["recording_format", "frame_format", "created", "robots", "bounds", "versions"],
    "properties": {
        "recording_format": _INT,
        "frame_format": _INT,
        "created": {"type": "string", "description": "ISO 8601 UTC start time"},
        "robots": _arr(_INT),
        "bounds": _arr({"type": "number"}, 4),
        "versions": {"type": "object", "additionalProperties": {"type": "string"}},
        "config": {"type": "object"},
    },
}

EVENT_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Event",
    "description": "A timestamped message: an operator action, a frame event or a recorder notice.",
    "type": "object",
    "required": ["t", "kind", "text"],
    "properties": {"t": {"type": "number"}, "kind": {"type": "string"}, "text": {"type": "string"}},
}

OPERATOR_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.OperatorEvent",
    "description": "One operator action (run, pause, step, e-stop, release, behaviour, parameters, bumps), "
                   "stamped with the tick that first ran with it and that tick's loop clock (s).",
    "type": "object",
    "required": ["tick", "time", "type"],
    "properties": {"tick": _INT, "time": {"type": "number"}, "type": {"type": "string"}},
}

#: topic -> (schema name, JSON schema)
CHANNELS: dict[str, tuple[str, dict[str, Any]]] = {
    TOPIC_CONFIG: ("swarmdeck.Config", CONFIG_SCHEMA),
    TOPIC_FRAME: ("swarmdeck.Frame", FRAME_SCHEMA),
    TOPIC_DATAGRAM: ("swarmdeck.Datagram", DATAGRAM_SCHEMA),
    TOPIC_EVENT: ("swarmdeck.Event", EVENT_SCHEMA),
    TOPIC_OPERATOR: ("swarmdeck.OperatorEvent", OPERATOR_SCHEMA),
}
