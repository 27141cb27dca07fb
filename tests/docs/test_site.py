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
