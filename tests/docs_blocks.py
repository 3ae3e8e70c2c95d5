"""The code examples of the documentation (``docs/*.md``): fenced blocks, what each is, and how to run them.

A block's info string says what it is: ```` ```python ```` and ```` ```bash ```` (``sh``, ``shell``) run; a block with a title (```` ```python title="f.py" ````, ```` ```toml title="c.toml" ````)
is written to that file instead (a later block of the page runs or reads it); ``{.bash .norun}`` / ``{.python .norun}``
marks one of the few blocks that cannot run in a test (a server that keeps running, an install); any other
language (``text``, ``toml``, ``ini``, ``json``) is shown output or configuration, not run. A page's blocks
run in order in one fresh folder. In a shell block every command line must be a ``swarmdeck`` command
(comments and continuation lines aside): nothing else of the machine is touched.
"""
from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"
SHELLS = ("bash", "sh", "shell")
RUNNABLE = ("python", *SHELLS)
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})(?P<info>[^`\n]*)$")


@dataclass(frozen=True)
class Block:
    """One fenced block: its page, the line of its opening fence (1-based), language, classes, title, code."""

    page: Path
    line: int
    lang: str
    classes: tuple[str, ...]
    title: str | None
    code: str

    @property
    def runs(self) -> bool:
        return self.lang in RUNNABLE and "norun" not in self.classes

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(DOCS.parent)}:{self.line}"


def parse_info(info: str) -> tuple[str, tuple[str, ...], str | None]:
    """(language, classes, title) of a fence's info string: ``python title="a.py"`` or ``{.bash .norun}``."""
    info = info.strip()
    title = re.search(r'title="([^"]*)"', info)
    if info.startswith("{"):
        classes = tuple(re.findall(r"\.([\w-]+)", info))
        return (classes[0] if classes else ""), classes[1:], title.group(1) if title else None
    lang = info.split()[0] if info else ""
    return lang, (), title.group(1) if title else None


def blocks(page: Path) -> list[Block]:
    """Every fenced block of ``page`` (indented fences inside lists too)."""
    out: list[Block] = []
    lines = page.read_text().splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m is None:
            i += 1
            continue
        indent, fence = m.group("indent"), m.group("fence")
        lang, classes, title = parse_info(m.group("info"))
        body = []
        j = i + 1
        while j < len(lines) and not (lines[j].strip().startswith(fence) and lines[j].strip().strip(fence[0]) == ""):
            body.append(lines[j][len(indent):] if lines[j].startswith(indent) else lines[j])
            j += 1
        out.append(Block(page, i + 1, lang, classes, title, textwrap.dedent("\n".join(body)) + "\n"))
        i = j + 1
    return out


def pages() -> list[Path]:
    return sorted(DOCS.rglob("*.md"))


def shell_commands(code: str) -> list[str]:
    """The commands of a shell block, continuation lines joined; comments dropped."""
    commands, current = [], ""
    for raw in code.splitlines():
        line = raw.split(" #", 1)[0].rstrip() if not raw.lstrip().startswith("#") else ""
        if not line.strip() and not current:
            continue
        current += line
        if current.endswith("\\"):
            current = current[:-1] + " "
            continue
        commands.append(current.strip())
        current = ""
    return commands
