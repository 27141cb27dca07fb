"""Every command and every Python snippet of the README and of every page under docs/
runs as written, each page in a scratch directory of its own that holds a copy of configs/
(later snippets of a page see the files earlier ones wrote, as a user following the page
would). See tests/docs/pages.py for what counts as a step. Pages whose runs take
long (sweeps, dynamic runs, the examples) are marked slow.
"""

from __future__ import annotations

import re
import shutil
import tomllib

import pytest
from pages import ROOT, page_id, pages, run_page, steps, toml_blocks

# Pages cheap enough for every test run (a few catenet commands each).
FAST = {
    "README.md",
    "docs/getting-started.md",
    "docs/howto/guyed-mast.md",
    "docs/howto/mooring-line.md",
    "docs/reference/errors.md",
    "docs/performance.md",
}
# What a page's run must leave behind, beyond its commands succeeding.
LEAVES = {
    "README.md": ["out/catenary.png", "out/saddle.toml"],
    "docs/validation.md": ["out/paper/report.md"],
    "docs/howto/cable-roof.md": ["out/snow.png"],
}


# Pages with a test of their own, which runs them and checks what they leave.
OWN = {
    "docs/guide/loads.md",
    "docs/guide/modes.md",
    "docs/guide/bodies.md",
    "docs/guide/results.md",
    "docs/guide/reliability.md",
    "docs/guide/supports.md",
}


def params(half: int):
    """The pages run here (``half`` 0) and in test_docs_more.py (``half`` 1): every
    other one, so that the two files' pages run on two workers side by side."""
    mine = [p for p in pages() if page_id(p) not in OWN]
    for path in mine[half::2]:
        name = page_id(path)
        marks = [] if name in FAST else [pytest.mark.slow]
        yield pytest.param(path, id=name, marks=marks)


def paper_study_as_documented(directory):
    """docs/validation.md's `catenet sweep configs/sweeps/paper.toml -o out/paper` and
    `catenet plot out/paper` (the README's study): 390 rows, the figures, and the numbers
    the README reports: the collapse onto delta_bar = C f(alpha) (F_bar/n)^beta holds to
    1 % RMS with beta = 1/3 and D = 1.21 (the paper: 1.31). (The study runs once in the
    suite, here.)"""
    from catenet.study import fit_scaling, load_data

    out = directory / "out" / "paper"
    d = load_data(out)
    assert d.rows == 390 and d.failed == 0
    fit = fit_scaling(d.F_bar, d.n, d.alpha, d.delta_bar)
    assert fit.D == pytest.approx(1.206, abs=0.01)
    assert fit.beta == pytest.approx(1 / 3, abs=0.005)
    assert fit.rms_log < 0.01
    for name in (
        "fig5_force_displacement_n",
        "fig6_force_displacement_alpha",
        "fig7_n_alpha",
        "fig8_scaling",
    ):
        assert (out / f"{name}.png").stat().st_size > 10_000
    assert "Does not agree" in (out / "report.md").read_text()  # D = 1.21, not 1.31


# What a page's run must give, checked on what it left (the directory it ran in).
CHECKS = {"docs/validation.md": paper_study_as_documented}


def check_page(path, tmp_path, monkeypatch):
    """The page's steps run in a scratch copy of configs/, and leave what it says."""
    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    monkeypatch.chdir(tmp_path)
    run_page(path, tmp_path)
    for left in LEAVES.get(page_id(path), []):
        assert (tmp_path / left).exists(), left
    if (check := CHECKS.get(page_id(path))) is not None:
        check(tmp_path)


def test_the_pages_have_steps():
    kinds = [s.kind for path in pages() for s in steps(path)]
    assert kinds.count("shell") >= 10 and kinds.count("python") >= 3
    readme = [s.kind for s in steps(ROOT / "README.md")]
    assert readme.count("shell") >= 4 and readme.count("python") >= 1
    assert set(FAST) | set(LEAVES) <= {page_id(p) for p in pages()}


@pytest.mark.parametrize("path", [p for p in pages() if toml_blocks(p)], ids=page_id)
def test_every_toml_block_parses(path):
    for line, text in toml_blocks(path):
        try:
            tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            pytest.fail(f"{page_id(path)}:{line}: {exc}")


@pytest.mark.parametrize("path", pages(), ids=page_id)
def test_every_link_to_a_file_of_the_repository_resolves(path):
    """Relative links and images point at files that exist (the site build checks the
    pages under docs/ too; this also covers the README)."""
    text = path.read_text(encoding="utf-8")
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        where = (path.parent / target.split("#")[0]).resolve()
        assert where.exists(), f"{page_id(path)}: link to {target}: no such file"


@pytest.mark.parametrize("path", list(params(0)))
def test_page_runs_as_written(path, tmp_path, monkeypatch):
    check_page(path, tmp_path, monkeypatch)


@pytest.mark.parametrize("name", ["Makefile", ".ci/run"])
def test_setup_files_do_what_the_quick_start_says(name):
    text = (ROOT / name).read_text()
    if name == "Makefile":
        assert re.search(r"^run:.*\n\t.*catenet run$", text, re.M)
        assert re.search(r"^test:.*\n\t.*pytest", text, re.M)
        assert "-m venv" in text
    else:
        assert "make test" in text


@pytest.mark.parametrize(
    "path", sorted((ROOT / "docs" / "examples").glob("[!i]*.md")), ids=lambda p: p.stem
)
def test_an_example_page_shows_its_case_file_as_it_is(path):
    """Each example page names its case in configs/, shows that file unchanged and the
    figure of it."""
    text = path.read_text(encoding="utf-8")
    (name,) = re.findall(r"^`(configs/[^`]+\.toml)`: ", text, re.M)
    (_, block), *_ = toml_blocks(path)
    assert block.rstrip() == (ROOT / name).read_text().rstrip()
    (figure,) = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", text)
    assert (path.parent / figure).exists()
