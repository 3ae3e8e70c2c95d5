"""While a run goes, the jail's copy of the researcher's script is readable by the run alone: no other local user
reads it (folders 0750 and files 0640, group the run's own gid, or 0700/0600 without a uid of its own). Asserted
from the trusted side while the script is alive, in both jails; the script still reads its sibling module."""
import os
import stat
import tempfile
from pathlib import Path

from jail_fixtures import plant


def _copies() -> list[Path]:
    return sorted(Path(tempfile.gettempdir()).glob("swarmdeck-script-*"))


def test_the_scripts_copy_is_private_to_the_run(jail_run):
    seen: list[tuple[str, int, int]] = []
    before = set(_copies())  # left by runs of other processes (or older versions): not this run's

    def watching_plant(n, initial):
        for folder in set(_copies()) - before:  # the script is alive now: it is building its Arena
            try:
                for path in [folder, *folder.rglob("*")]:
                    st = path.lstat()
                    seen.append((str(path), stat.S_IMODE(st.st_mode), st.st_gid))
            except FileNotFoundError:  # another test's run ended meanwhile
                continue
        return plant(n, initial)

    out = jail_run("""
        import os
        print("READ", len(open(__file__).read()) > 0)
        def experiment(arena):
            arena.step()
    """, make_plant=watching_plant)
    assert out.ok, out.error
    assert "READ True" in out.log
    assert seen, "the run's copy of the script must exist while it runs"
    world = [(p, oct(m)) for p, m, _ in seen if m & 0o007]
    assert not world, f"readable by other local users: {world}"
    if os.geteuid() == 0:  # a uid of the run's own: only its group may read
        assert all(g != 0 for _, _, g in seen), seen
