"""The run report as one self-contained HTML page (``cablesim report``).

The page needs nothing but itself: styles inline, figures embedded as base64 ``data:`` images,
no script or font fetched from anywhere. It reads on a phone (the text reflows, wide tables
scroll sideways, figures shrink to the screen) and prints (one file per page, figures never
split). A short inline script counts the figures the browser decoded into the ``<body>``'s
``data-figures-loaded`` attribute (``data-figures`` holds how many there are), so that a
headless browser can check them.
"""

from __future__ import annotations

import base64
import datetime
import html
from pathlib import Path

from ..version import __version__
from .paths import part_path, remove_stale_parts, write_error
from .report_tables import FileReport, Table

STYLE = """
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; line-height: 1.45;
       color: #1b1b1b; background: #fff; max-width: 60rem; margin: 0 auto; padding: 0.8rem 1rem 3rem; }
h1 { font-size: 1.5rem; margin: 0.4rem 0; } h2 { font-size: 1.25rem; margin-top: 2.2rem;
  border-bottom: 2px solid #1f5fa8; padding-bottom: 0.2rem; } h3 { font-size: 1.05rem; margin: 1.4rem 0 0.4rem; }
.meta { color: #555; font-size: 0.9rem; }
nav ol { padding-left: 1.4rem; } nav a { color: #1f5fa8; }
.scroll { overflow-x: auto; -webkit-overflow-scrolling: touch; margin: 0.3rem 0 0.2rem; }
table { border-collapse: collapse; font-size: 0.88rem; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #c8c8c8; padding: 0.2rem 0.5rem; text-align: right; white-space: nowrap; }
th { background: #eef3f9; } td.t { text-align: left; white-space: normal; }
table.kv td:first-child { text-align: left; font-weight: 600; white-space: nowrap; }
table.kv td { text-align: left; white-space: normal; word-break: break-word; }
caption { text-align: left; font-weight: 600; padding: 0.3rem 0; }
p.note { font-size: 0.85rem; color: #444; margin: 0.1rem 0 0.8rem; }
.warnings { border: 2px solid #d62728; border-radius: 4px; padding: 0.4rem 0.8rem; background: #fff5f5; }
.warnings h3 { color: #d62728; margin: 0.2rem 0; } .ok { color: #2a6e3a; }
pre { background: #f6f6f6; padding: 0.6rem; overflow-x: auto; font-size: 0.8rem; }
figure { margin: 1rem 0; } figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.85rem; color: #444; }
@media (max-width: 40rem) { body { padding: 0.5rem; } table { font-size: 0.8rem; } }
@media print { nav { display: none; } section.file { break-before: page; } figure, table { break-inside: avoid; }
  details { display: block; } details > summary { list-style: none; } h2 { border-color: #000; }
  body { max-width: none; } }
"""

SCRIPT = """
window.addEventListener("load", function () {
  var imgs = document.images, n = 0;
  for (var i = 0; i < imgs.length; i++) { if (imgs[i].complete && imgs[i].naturalWidth > 0) n++; }
  document.body.setAttribute("data-figures-loaded", String(n));
});
"""


def esc(value) -> str:
    """HTML-escaped text."""
    return html.escape(str(value), quote=True)


def table_html(t: Table, prefix: str) -> str:
    """One result table; each number's cell holds the number at full precision in ``data-value``."""
    head = "".join(f"<th>{esc(c)}</th>" for c in t.columns)
    rows = []
    for row in t.rows:
        cells = []
        for c in row:
            if c.value is None:
                cells.append(f'<td class="t">{esc(c.text)}</td>')
            else:
                cells.append(f'<td data-value="{c.value!r}">{esc(c.text)}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    note = f'<p class="note">{esc(t.note)}</p>' if t.note else ""
    return (f'<div class="scroll"><table id="{esc(prefix)}-{esc(t.key)}" data-table="{esc(t.key)}">'
            f"<caption>{esc(t.title)}</caption><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody>"
            f"</table></div>{note}")


def kv_html(pairs, key: str) -> str:
    """A two-column table of labels and values."""
    rows = "".join(f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>" for k, v in pairs)
    return f'<div class="scroll"><table class="kv" id="{esc(key)}"><tbody>{rows}</tbody></table></div>'


def figure_html(caption: str, mime: str, data: bytes) -> str:
    """A figure embedded as a ``data:`` URI."""
    b64 = base64.b64encode(data).decode("ascii")
    return (f'<figure><img src="data:{mime};base64,{b64}" alt="{esc(caption)}" loading="eager">'
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def warnings_html(warnings: list[str], key: str) -> str:
    """The warnings of a file (or a line saying there are none)."""
    if not warnings:
        return f'<p class="ok" id="{esc(key)}">No warnings.</p>'
    items = "".join(f"<li>{esc(w)}</li>" for w in warnings)
    return f'<div class="warnings" id="{esc(key)}"><h3>Warnings</h3><ul>{items}</ul></div>'


def file_section(k: int, rep: FileReport, figures) -> str:
    """The section of one result file: warnings, how it was run, the case, tables, figures."""
    key = f"f{k}"
    parts = [f'<section class="file" id="{key}"><h2>{k}. {esc(rep.command)}: {esc(rep.path.name)}</h2>',
             f'<p class="meta">{esc(rep.path)}</p>', warnings_html(rep.warnings, f"{key}-warnings"),
             "<h3>How it was run</h3>", kv_html(rep.provenance, f"{key}-provenance"),
             f"<details><summary>Every effective option</summary><pre>{esc(rep.options)}</pre></details>",
             "<h3>The case</h3>", kv_html(rep.case_summary, f"{key}-case"),
             f"<details><summary>The case file as it ran</summary><pre>{esc(rep.case_text)}</pre></details>",
             "<h3>Results</h3>"]
    for t in rep.tables:
        if t.key == "datasets":
            parts.append(f"<details><summary>{esc(t.title)}</summary>{table_html(t, key)}</details>")
        else:
            parts.append(table_html(t, key))
    parts.append(f"<h3>Figures ({len(figures)})</h3>")
    parts += [figure_html(*fig) for fig in figures] or ['<p class="note">No figures.</p>']
    parts.append("</section>")
    return "\n".join(parts)


def render_report(reports: list[FileReport], figures: list[list[tuple[str, str, bytes]]], title: str) -> str:
    """The whole page: a title, a table of contents and one section per result file.

    Parameters
    ----------
    reports : list of FileReport
    figures : list of list of (caption, MIME type, bytes)
        Per file, its figures.
    title : str
        The page's title (the case name).
    """
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    count = sum(len(f) for f in figures)
    toc = "".join(f'<li><a href="#f{k}">{esc(r.command)}: {esc(r.path.name)}</a>'
                  f"{f' ({len(r.warnings)} warning' + ('s' if len(r.warnings) > 1 else '') + ')' if r.warnings else ''}</li>"
                  for k, r in enumerate(reports, start=1))
    body = "\n".join(file_section(k, r, f) for k, (r, f) in enumerate(zip(reports, figures), start=1))
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{esc(title)}: cablesim report</title><style>{STYLE}</style></head>\n"
            f'<body data-figures="{count}"><header><h1>{esc(title)}: cablesim report</h1>'
            f'<p class="meta">Written {now} by cablesim {esc(__version__)} from {len(reports)} result '
            f"file{'s' if len(reports) != 1 else ''}; {count} figures.</p></header>"
            f"<nav><ol>{toc}</ol></nav>\n{body}\n<script>{SCRIPT}</script></body></html>\n")


def write_report_html(path: str | Path, text: str) -> Path:
    """Write the page atomically (through ``NAME.part``)."""
    path = Path(path)
    remove_stale_parts(path)
    tmp = part_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(path)
    except OSError as exc:
        raise write_error(path, exc) from None
    finally:
        tmp.unlink(missing_ok=True)
    return path
