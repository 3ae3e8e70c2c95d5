"""A bad value in the console's config file is named by the key the user wrote (``robots``, not ``n_robots``)."""
from __future__ import annotations

import pytest

from swarmdeck.console.runtime.config import ConfigFileError, load_settings


@pytest.mark.parametrize("body, key", [
    ('robots = "many"', "robots"),
    ("robots = -3", "robots"),
    ("robots = 2.5", "robots"),
    ("dt = 9", "dt"),
    ("max_speed = 0", "max_speed"),
    ("script_budget = 2", "script_budget"),
])
def test_a_bad_console_value_names_the_key_written(tmp_path, body: str, key: str) -> None:
    p = tmp_path / "c.toml"
    p.write_text(f"[console]\n{body}\n")
    with pytest.raises(ConfigFileError) as info:
        load_settings(p)
    msg = str(info.value)
    assert f"[console] {key}" in msg and "n_robots" not in msg and str(p) in msg, msg


def test_script_budget_is_read_from_the_file(tmp_path) -> None:
    p = tmp_path / "c.toml"
    p.write_text("[console]\nrobots = 5\nscript_budget = 0.01\n")
    s = load_settings(p)
    assert s.loop.n_robots == 5 and s.loop.script_budget_s == 0.01
