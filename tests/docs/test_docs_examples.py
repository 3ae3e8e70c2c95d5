"""Every code example in the documentation runs as written (see tests/docs_blocks.py for the rules): each page's
Python blocks in a fresh interpreter and its shell blocks' ``swarmdeck`` commands, in order, in a fresh folder."""
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from docs_blocks import DOCS, SHELLS, blocks, pages, shell_commands

BIN = Path(sys.executable).parent
PAGES = [p for p in pages() if any(b.runs or b.title for b in blocks(p))]
NORUN_BUDGET = 13  # blocks marked .norun across the site: few, each a server, a runner, an install or a service file


def run(argv, cwd, what, timeout=240):
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}", "MPLBACKEND": "Agg"}
    out = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == 0, f"{what} failed (exit {out.returncode}):\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    return out


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_the_pages_examples_run(page, tmp_path):
    found = blocks(page)
    for k, block in enumerate(found):
        if "norun" in block.classes:
            continue
        if block.title:  # a file (any language) a later block runs
            assert any(block.title in later.code for later in found[k + 1:] if later.runs), \
                f"{block.where}: no later block of the page uses {block.title}"
            (tmp_path / block.title).write_text(block.code)
        elif not block.runs:
            continue
        elif block.lang == "python":
            run([sys.executable, "-c", block.code], tmp_path, f"the Python block at {block.where}")
        else:
            for command in shell_commands(block.code):
                words = shlex.split(command)
                assert words[0] == "swarmdeck", (f"{block.where}: only swarmdeck commands run in the docs' shell "
                                                 f"blocks; mark the block .norun if it cannot run: {command!r}")
                run([str(BIN / "swarmdeck"), *words[1:]], tmp_path, f"{command!r} at {block.where}")


def test_only_a_few_blocks_are_not_run():
    norun = [b.where for p in pages() for b in blocks(p) if "norun" in b.classes]
    assert len(norun) <= NORUN_BUDGET, norun
    languages = {b.lang for p in pages() for b in blocks(p)}
    known = {"python", *SHELLS, "text", "toml", "ini", "json", "yaml", "caddy", "nginx", "html", ""}
    assert languages <= known, f"unknown languages (a typo would silently not run): {languages - known}"
