"""The newmark integrator in contact: at its default rho_inf (0.8) it gains momentum in
impacts and does not converge with the step, and at any rho_inf its steps can fail at
first contact (docs/howto/dynamic-runs.md), so a case with contact (an obstacle, a free
body, self-contact) that asks for it exits 2, naming bdf2 and implicit Euler."""

from __future__ import annotations

import pytest
from click.testing import CliRunner
from conftest import small_net

from catenet.case import load_case
from catenet.case.kinds import warn
from catenet.cli import main
from catenet.errors import ConfigError

SPHERE = """
[[obstacle]]
kind = "sphere"
center = [0.0, 0.0, -2.0]
radius = 0.5
"""
NEWMARK = small_net(method="dynamic", dt=0.01, t_end=0.03) + SPHERE
NEWMARK = NEWMARK.replace('method = "dynamic"', 'method = "dynamic"\nintegrator = "newmark"')


@pytest.fixture(autouse=True)
def fresh_warnings():
    warn._WARNED.clear()
    yield
    warn._WARNED.clear()


def refused(tmp_path, write_case, text, *sets):
    """The output of ``catenet run`` on the case, which must exit 2."""
    args = ["run", str(write_case(text)), "-o", str(tmp_path / "out.h5")]
    for item in sets:
        args += ["--set", item]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    return r.output


def test_newmark_with_an_obstacle_exits_2(tmp_path, write_case):
    out = refused(tmp_path, write_case, NEWMARK)
    assert "solver.integrator = 'newmark': not for a run with contact (obstacle[0] (sphere))" in out
    assert "'bdf2'" in out and "'implicit_euler'" in out
    with pytest.raises(ConfigError, match="gains momentum in impacts"):
        load_case(write_case(NEWMARK), ("solver.rho_inf=0.5",))


def test_free_bodies_and_self_contact_exit_2(tmp_path, write_case):
    body = NEWMARK.replace("radius = 0.5", "radius = 0.5\nmass = 5.0")
    assert "obstacle[0] (sphere)" in refused(tmp_path, write_case, body)
    free = NEWMARK.replace(SPHERE, "").replace("[solver]", "[solver]\nself_contact = true")
    assert "(solver.self_contact)" in refused(tmp_path, write_case, free)


@pytest.mark.parametrize(
    "text, sets",
    [
        (NEWMARK, ('solver.integrator="implicit_euler"',)),
        (NEWMARK, ('solver.method="static"',)),
        (NEWMARK.replace(SPHERE, ""), ()),  # no contact
    ],
)
def test_newmark_without_contact_and_contact_without_newmark_run(write_case, text, sets):
    assert load_case(write_case(text), sets).solver is not None
