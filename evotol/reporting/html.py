"""Offline HTML reports built from plotly figures and tables.

plotly.js (4.8 MB) is written once per folder, as ``plotly-<version>.min.js`` beside the reports
that use it, and each page loads it with a relative ``<script src>`` (no CDN): the reports of one
``evotol reproduce all`` share one copy, and the folder opens from disk on a machine with no
network. ``Report.write(path, inline_plotly=True)`` embeds it instead, for a single file to send
on its own. Figures are added with :meth:`Report.figure`, prose with :meth:`Report.text`, tables
with :meth:`Report.table`.
"""
from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from evotol._runtime.atomic_files import write_bytes, write_text

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;max-width:1200px;
     padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em} h2{font-size:1.25em;margin-top:1.8em;border-bottom:1px solid #ddd}
table.ev{border-collapse:collapse;margin:.6em 0;font-size:.9em}
table.ev th,table.ev td{border:1px solid #ccc;padding:.25em .6em;text-align:right}
table.ev th{background:#f3f3f3} table.ev td:first-child,table.ev th:first-child{text-align:left}
.note{background:#fff8e1;border-left:4px solid #f0b400;padding:.5em 1em;margin:1em 0}
.ok{color:#1b7f2a;font-weight:600} .bad{color:#b00020;font-weight:600}
.meta{color:#666;font-size:.85em}
"""


def plotlyjs_name() -> str:
    """File name of the shared plotly.js bundle, versioned so that reports of different plotly
    versions in one folder do not overwrite each other's copy.

    Returns
    -------
    str
        ``"plotly-<version>.min.js"``, the version of the plotly.js bundled with plotly.
    """
    from plotly.offline import get_plotlyjs_version

    return f"plotly-{get_plotlyjs_version()}.min.js"


def write_plotlyjs(folder: str | Path) -> Path:
    """Write the plotly.js bundle into ``folder`` unless an identical copy is there already
    (atomic: parallel writers of one folder never leave a half-written file).

    A copy of the same size counts as identical.

    Parameters
    ----------
    folder : str or Path
        The folder of the reports (created when missing).

    Returns
    -------
    Path
        Path of the bundle, ``folder / plotlyjs_name()``.
    """
    from plotly.offline import get_plotlyjs

    folder = Path(folder)
    path = folder / plotlyjs_name()
    js = get_plotlyjs().encode("utf-8")
    if not (path.exists() and path.stat().st_size == len(js)):
        folder.mkdir(parents=True, exist_ok=True)
        write_bytes(path, js, record=False)   # shared by every report of the folder: no output set's file
    return path


def _fmt(v, digits: int = 4) -> str:
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            return html.escape(str(v))
        if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5):
            return f"{v:.{digits}e}"
        return f"{v:.{digits}g}"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    return html.escape(str(v))


def table_html(rows: Sequence[Sequence], header: Sequence[str] | None = None, digits: int = 4,
               table_id: str | None = None) -> str:
    """An HTML table; floats are printed with ``digits`` significant digits.

    Floats below 1e-3 or from 1e5 in magnitude are printed in exponent notation, booleans as
    yes/no; other values as text, HTML-escaped.

    Parameters
    ----------
    rows : sequence of sequence
        The cells, row by row (values as they are, no unit conversion).
    header : sequence of str, optional
        Column titles; no header row when None or empty.
    digits : int, default 4
        Significant digits of floats.
    table_id : str, optional
        ``id`` attribute of the ``<table>`` (for scripts of the page).

    Returns
    -------
    str
        The ``<table class="ev">`` element.
    """
    out = [f'<table class="ev"{f" id={html.escape(table_id)!r}" if table_id else ""}>']
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{_fmt(v, digits)}</td>" for v in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


class Report:
    """Collects sections and writes one self-contained HTML file.

    Sections are added in page order by :meth:`heading`, :meth:`text`, :meth:`table`,
    :meth:`figure` and :meth:`html`; :meth:`write` writes the page (plotly.js beside it unless
    ``inline_plotly``).

    Parameters
    ----------
    title : str
        Page title (``<title>`` and the ``<h1>`` heading).
    subtitle : str, default ""
        A line of small print under the title; none when empty.
    """

    def __init__(self, title: str, subtitle: str = ""):
        self.title, self.subtitle = title, subtitle
        self._parts: list[str] = []
        self._n_fig = 0

    def heading(self, text: str) -> "Report":
        """Add a section heading (``<h2>``).

        Parameters
        ----------
        text : str
            The heading (HTML-escaped).

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        self._parts.append(f"<h2>{html.escape(text)}</h2>")
        return self

    def lead(self, text: str) -> "Report":
        """Put a highlighted note first, under the title (before every section added so far).

        Parameters
        ----------
        text : str
            The prose (HTML-escaped).

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        self._parts.insert(0, f'<div class="note">{html.escape(text)}</div>')
        return self

    def text(self, text: str, note: bool = False, raw: bool = False) -> "Report":
        """Add a paragraph, or a highlighted note.

        Parameters
        ----------
        text : str
            The prose.
        note : bool, default False
            Show it as a highlighted note box instead of a paragraph.
        raw : bool, default False
            ``text`` is HTML and inserted as it is (else it is escaped).

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        body = text if raw else html.escape(text)
        self._parts.append(f'<div class="note">{body}</div>' if note else f"<p>{body}</p>")
        return self

    def html(self, fragment: str) -> "Report":
        """Add an HTML fragment as it is (no escaping).

        Parameters
        ----------
        fragment : str
            The HTML.

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        self._parts.append(fragment)
        return self

    def table(self, rows, header=None, digits: int = 4, table_id: str | None = None) -> "Report":
        """Add a table (:func:`table_html`).

        Parameters
        ----------
        rows : sequence of sequence
            The cells, row by row.
        header : sequence of str, optional
            Column titles.
        digits : int, default 4
            Significant digits of floats.
        table_id : str, optional
            ``id`` attribute of the table.

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        self._parts.append(table_html(rows, header, digits, table_id))
        return self

    def figure(self, fig, div_id: str | None = None) -> "Report":
        """Add a plotly figure (responsive, drawn by the page's plotly.js).

        Parameters
        ----------
        fig : plotly.graph_objects.Figure
            The figure.
        div_id : str, optional
            ``id`` of its ``<div>``; by default ``fig<k>`` for the k-th figure added.

        Returns
        -------
        Report
            This report, so that calls chain.
        """
        self._n_fig += 1
        div_id = div_id or f"fig{self._n_fig}"
        self._parts.append(fig.to_html(full_html=False, include_plotlyjs=False, div_id=div_id,
                                       config={"responsive": True, "displaylogo": False}))
        return self

    def render(self, inline_plotly: bool = False) -> str:
        """The page; plotly.js is loaded from :func:`plotlyjs_name` beside it, or embedded.

        Parameters
        ----------
        inline_plotly : bool, default False
            Embed plotly.js (4.8 MB) in the page instead of loading the file beside it.

        Returns
        -------
        str
            The HTML document.
        """
        if inline_plotly:
            from plotly.offline import get_plotlyjs

            script = f"<script type=\"text/javascript\">{get_plotlyjs()}</script>"
        else:
            script = f"<script type=\"text/javascript\" src=\"{plotlyjs_name()}\" charset=\"utf-8\"></script>"
        sub = f'<p class="meta">{html.escape(self.subtitle)}</p>' if self.subtitle else ""
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{html.escape(self.title)}</title><style>{_CSS}</style>"
                f"{script}</head><body>"
                f"<h1>{html.escape(self.title)}</h1>{sub}" + "\n".join(self._parts) + "</body></html>")

    def write(self, path: str | Path, inline_plotly: bool = False) -> Path:
        """Write the page to ``path`` and, unless ``inline_plotly``, the shared plotly.js beside it.

        Parameters
        ----------
        path : str or Path
            The HTML file (missing parent folders are created; an existing file is replaced).
        inline_plotly : bool, default False
            Embed plotly.js in the page (a single file to send on its own).

        Returns
        -------
        Path
            ``path``.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        if not inline_plotly:
            write_plotlyjs(path.parent)
        write_text(path, self.render(inline_plotly))     # the page as one string, renamed into place whole
        return path


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        if all(type(v) is float or type(v) is int for v in obj):     # a list of numbers: no call per number
            return [v if type(v) is int or math.isfinite(v) else None for v in obj]
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "iu":
            return obj.tolist()
        if obj.dtype.kind == "f" and obj.ndim and np.isfinite(obj).all():
            return obj.tolist()
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    return obj


def write_json(path: str | Path, data: dict) -> Path:
    """Write ``data`` as JSON; numpy values are converted, non-finite floats become null.

    Dict keys become strings, tuples and arrays lists.

    Parameters
    ----------
    path : str or Path
        The JSON file (missing parent folders are created).
    data : dict
        The data (nested dicts, lists, numbers, strings, numpy arrays and scalars).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json_text(data))
    return path


def json_text(data: dict) -> str:
    """``data`` as the JSON text :func:`write_json` writes (numpy values converted, non-finite
    floats as null), for a command that prints it (``--json``).

    Parameters
    ----------
    data : dict
        As for :func:`write_json`.

    Returns
    -------
    str
        The JSON text (indent 1).
    """
    return json.dumps(_jsonable(data), indent=1)
