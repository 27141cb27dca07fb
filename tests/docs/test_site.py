"""The documentation site builds: ``mkdocs build --strict`` (what ``make docs`` runs), offline,
with every page of docs/ in it and no broken link or missing image."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from pages import ROOT


def test_the_site_builds_strict_and_offline(tmp_path):
    pytest.importorskip("mkdocs", reason="mkdocs is in the test and docs extras")
    site = tmp_path / "site"
    env = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
    env.update(HTTP_PROXY="http://127.0.0.1:9", HTTPS_PROXY="http://127.0.0.1:9")  # offline
    # (no -q: it hides the warnings that --strict fails on)
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    built = {p.relative_to(site).with_suffix(".md") for p in site.rglob("*.html")}
    for page in (ROOT / "docs").rglob("*.md"):
        assert page.relative_to(ROOT / "docs") in built, page
    assert (site / "search" / "search_index.json").exists()
    assert "Getting started" in (site / "index.html").read_text()
    theory = (site / "theory.html").read_text()  # its maths as MathML, none left as LaTeX
    assert theory.count('<math xmlns="http://www.w3.org/1998/Math/MathML"') >= 10
    assert "$$" not in theory and "\\(" not in theory and "\\frac" not in theory


def test_the_maths_hook_makes_mathml_and_leaves_code_alone():
    sys.path.insert(0, str(ROOT / "docs" / "hooks"))
    from maths import to_mathml

    text = (
        "A \\(\\epsilon = 1\\) here,\n\n$$\nE = \\frac{1}{2} k x^2\n$$\n\n"
        "`\\(a\\)` and\n```\n$$\nx\n$$\n```\n"
    )
    out = to_mathml(text)
    assert out.count("<math") == 2 and 'display="block"' in out and 'display="inline"' in out
    assert "<mfrac>" in out and "`\\(a\\)`" in out and "```\n$$\nx\n$$\n```" in out
    with pytest.raises(ValueError, match="page.md: a formula"):
        to_mathml("$$\n\\frac{1}{\n$$", "page.md")
