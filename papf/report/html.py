"""``report.html``: the report as one self-contained file a browser opens — the text and
tables of ``report.md`` (rendered by markdown-it-py, raw HTML off: a recording's world
name or reason is text, never markup) with every figure embedded as a ``data:`` URI, so
the file can be mailed or copied alone."""

from __future__ import annotations

import base64
import html
from pathlib import Path

from markdown_it import MarkdownIt

STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 72em; padding: 0 1em;
       line-height: 1.45; color: #222; }
table { border-collapse: collapse; margin: 1em 0; display: block; overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; white-space: nowrap; }
th { background: #f3f3f3; }
td:first-child, th:first-child { text-align: left; }
img { max-width: 100%; height: auto; border: 1px solid #eee; }
code { background: #f5f5f5; padding: 0 0.2em; }
"""


def report_html(markdown_text: str, images: dict[str, Path], title: str) -> str:
    """The page of ``markdown_text``; an image whose source is a key of ``images`` (a file
    name the report wrote) is embedded from that file, any other source left as written."""
    md = MarkdownIt("commonmark", {"html": False}).enable("table")
    default_image = md.renderer.rules["image"]

    def image(tokens, idx, options, env):
        token = tokens[idx]
        src = str(token.attrGet("src") or "")
        if src in images:
            data = base64.b64encode(images[src].read_bytes()).decode("ascii")
            token.attrSet("src", f"data:image/png;base64,{data}")
        return default_image(tokens, idx, options, env)

    md.renderer.rules["image"] = image
    body = md.render(markdown_text)
    return (f"<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n<style>{STYLE}</style>\n</head>\n"
            f"<body>\n{body}</body>\n</html>\n")
