"""docs/reference/cli.md is what the click commands say (regenerate it with
`python -m catenet.cli.reference docs/reference/cli.md`)."""

from __future__ import annotations

from pathlib import Path

from catenet.cli import COMMANDS
from catenet.cli.reference import help_text, page

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "cli.md"


def test_the_cli_reference_is_current():
    assert PAGE.read_text(encoding="utf-8") == page()


def test_the_reference_has_every_command_and_its_options():
    text = page()
    for name in COMMANDS:
        assert f"## catenet {name}\n" in text
        assert f"Usage: catenet {name} [OPTIONS]" in help_text(name)
    assert "--set KEY.PATH=VALUE" in help_text("run")
    assert "-o, --output" in help_text("bench")
