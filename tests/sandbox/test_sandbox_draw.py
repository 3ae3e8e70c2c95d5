"""What a sandboxed script draws crosses the trust boundary as data (issue 29 item 3): ``draw`` messages
before its commands, structure checked by the protocol, values capped on the trusted side (NaN refused,
clipped to the arena, a huge radius clipped, counted as events); a malformed message ends the run with what
was wrong, never the parent."""
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.protocol import ProtocolError, decode_draw, encode_annotations
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.core.annotations import CIRCLE, POINT, TEXT, Annotations
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def test_draw_messages_round_trip_and_malformed_ones_are_protocol_errors():
    a = Annotations(kinds=[POINT, TEXT], offsets=[0, 1, 2], vertices=[[0.25, 0.5], [-1.0, 0.75]], sizes=[0.02, 0.1],
                    colors=[[1, 2, 3, 4], [5, 6, 7, 8]], filled=[True, False], texts=("", "hi"))
    b = decode_draw(encode_annotations(a))
    assert b.vertices.tolist() == a.vertices.tolist() and b.texts == a.texts and b.colors.tolist() == a.colors.tolist()
    good = encode_annotations(a)
    for key, value, match in (("vertices", b"\x00" * 7, "vertices"), ("texts", [1], "texts"),
                              ("offsets", np.array([0, 5, 2], "<i4").tobytes(), "offsets"), ("kinds", "x", "kinds")):
        with pytest.raises(ProtocolError, match=match):
            decode_draw({**good, key: value})


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=1), duration=60.0))


@confined
def test_a_sandboxed_script_draws_on_the_trusted_arena_within_the_caps(tmp_path):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent("""
        import numpy as np
        def experiment(arena):
            arena.draw.circle((0.5, 0.25), 0.1, color="red", key="goal")
            for k in range(5):
                arena.draw.text((0.0, 0.0), f"step {k}", key="caption")
                arena.step()
            send = arena.backend.send_annotations  # the child's side is the script's to subvert:
            arena.backend.send_annotations = lambda ann: None  # the trusted side caps what arrives
            send(type(arena.last_annotations)(
                kinds=[0, 2], offsets=[0, 1, 2], vertices=[[float("nan"), 0.0], [9.0, 0.0]], sizes=[0.01, 1e9],
                colors=[[0, 0, 0, 255]] * 2, filled=[True, False], texts=("", "")))
            arena.step()
            arena.step()
    """))
    seen = []

    def watching(n, initial):
        p = plant(n, initial)
        arena = p.arena
        step = arena.step

        def recorded():
            out = step()
            seen.append(arena.last_annotations)
            return out

        arena.step = recorded
        return p

    out = run_sandboxed(script, watching, n_robots=2, duration=60.0)
    assert out.ended_by == "script", out.error_line
    assert len(seen) == 7
    assert seen[0].kinds.tolist() == [CIRCLE, TEXT] and seen[4].texts == ("", "step 4")
    assert seen[0].colors[0].tolist() == [214, 39, 40, 255] and seen[0].anchors()[0].tolist() == [0.5, 0.25]
    last = seen[5]  # the hostile drawing: the NaN point refused, the circle moved into the arena and shrunk
    assert last.kinds.tolist() == [CIRCLE] and last.anchors()[0].tolist() == [1.6, 0.0]
    assert last.sizes[0] == pytest.approx(np.hypot(3.2, 2.0))
    events = " ".join(out.plant.arena.events)
    assert "NaN/inf" in events and "arena diagonal" in events and "outside the arena" in events


@confined
def test_a_malformed_draw_message_ends_the_run_with_what_was_wrong(tmp_path):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent("""
        def experiment(arena):
            arena.step()
            arena.backend.link.send({"t": "draw", "kinds": b"\\x00", "offsets": b"\\x00\\x00", "vertices": b"",
                                     "sizes": b"", "colors": b"", "filled": b"", "texts": []})
            arena.step()
    """))
    out = run_sandboxed(script, plant, n_robots=2, duration=60.0)
    assert out.ended_by == "protocol" and "'draw' message" in out.error_line
