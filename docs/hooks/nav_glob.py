"""An MkDocs hook (mkdocs.yml ``hooks:``): a nav entry with a wildcard, such as
``guide/*.md``, becomes every page it matches under docs/, in file-name order, each titled
by its first heading; an entry that matches nothing is dropped. (MkDocs' own nav takes
literal paths only, and this needs no plugin.)"""

from __future__ import annotations

import glob
import os


def _title(path: str) -> str:
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("# "):
                return line[2:].strip()
    return os.path.splitext(os.path.basename(path))[0]


def _expand(items, docs_dir: str) -> list:
    out = []
    for item in items:
        if isinstance(item, dict):
            ((title, value),) = item.items()
            if isinstance(value, list):
                out.append({title: _expand(value, docs_dir)})
            elif isinstance(value, str) and any(c in value for c in "*?["):
                pages = _pages(value, docs_dir)
                if pages:
                    out.append({title: pages})
            else:
                out.append(item)
        elif isinstance(item, str) and any(c in item for c in "*?["):
            out += _pages(item, docs_dir)
        else:
            out.append(item)
    return out


def _pages(pattern: str, docs_dir: str) -> list:
    found = sorted(glob.glob(os.path.join(docs_dir, pattern)))
    return [{_title(p): os.path.relpath(p, docs_dir).replace(os.sep, "/")} for p in found]


def on_config(config, **kwargs):
    if config.nav:
        config.nav = _expand(config.nav, config.docs_dir)
    return config
