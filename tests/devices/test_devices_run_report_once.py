"""A script that calls call_at_scripts_end() under `swarmdeck run` gets its run report printed once."""
import textwrap

from swarmdeck.console.cli import main

SCRIPTS = {
    "rps": """
        import numpy as np
        import rps.robotarium as robotarium
        r = robotarium.Robotarium(number_of_robots=2, show_figure=False)
        for _ in range(3):
            r.get_poses()
            r.step()
        r.call_at_scripts_end()
    """,
    "arena": """
        from swarmdeck.devices import Arena
        arena = Arena(2)
        arena.step()
        arena.call_at_scripts_end()
    """,
}


def test_call_at_scripts_end_does_not_print_the_report_a_second_time(tmp_path, capsys):
    for name, text in SCRIPTS.items():
        script = tmp_path / f"{name}.py"
        script.write_text(textwrap.dedent(text))
        assert main(["run", str(script)]) == 0
        assert capsys.readouterr().out.count("swarmdeck run report") == 1, name
