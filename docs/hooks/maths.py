"""An MkDocs hook (mkdocs.yml ``hooks:``): maths written in LaTeX becomes MathML when the
site is built, which browsers render without a script or a network: ``$$ ... $$`` on lines
of their own is a displayed formula, ``\\( ... \\)`` an inline one. Code (fenced blocks and
`spans`) is left as written. A formula latex2mathml cannot read stops the build, naming
the page."""

from __future__ import annotations

import re

from latex2mathml.converter import convert

DISPLAY = re.compile(r"^\$\$\n(.+?)\n\$\$$", re.S | re.M)
INLINE = re.compile(r"\\\((.+?)\\\)")
CODE = re.compile(r"(^```.*?^```$|`[^`\n]+`)", re.S | re.M)


def _mathml(latex: str, display: bool, page: str) -> str:
    try:
        return convert(latex.strip(), display="block" if display else "inline")
    except Exception as exc:  # latex2mathml's own errors have no common base
        raise ValueError(f"{page}: a formula MathML cannot be made of: {latex!r}: {exc}") from exc


def to_mathml(markdown: str, page: str = "<page>") -> str:
    """``markdown`` with its formulas as MathML (module docstring)."""
    parts = CODE.split(markdown)
    for k in range(0, len(parts), 2):  # the even parts lie outside code
        text = DISPLAY.sub(lambda m: _mathml(m.group(1), True, page), parts[k])
        parts[k] = INLINE.sub(lambda m: _mathml(m.group(1), False, page), text)
    return "".join(parts)


def on_page_markdown(markdown, page, config, files):
    return to_mathml(markdown, page.file.src_path)
