"""``catenet plot`` on a file of ``catenet modes``: the modes figure beside the usual one."""

from __future__ import annotations

import subprocess

from tests.conftest import catenet_command, subprocess_env

CASE = """\
[geometry]
kind = "cable"
start = [0, 0, 0]
end = [12, 0, 0]
nodes = 25

[material]
EA = 1e6
area = 1e-4
density = 7850.0
prestress = 1500.0

[output]
file = "out/c.h5"
every = 0
"""


def test_plot_draws_the_lowest_modes(tmp_path):
    (tmp_path / "c.toml").write_text(CASE)
    env = subprocess_env()
    done = subprocess.run(catenet_command("modes", "c.toml", "-k", "4", "-q"), cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    drawn = subprocess.run(catenet_command("plot", "out/c.h5"), cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=300)  # fmt: skip
    assert drawn.returncode == 0, drawn.stderr
    assert drawn.stdout.split() == ["out/c.png", "out/c-modes.png"]
    png = (tmp_path / "out" / "c-modes.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
