"""Reports share one plotly.js beside them and open offline from disk (issue 11 item 7)."""
import re

import plotly.graph_objects as go
from plotly.offline import get_plotlyjs

from tests.browser import require_chromium
from evotol.reporting.html import Report, plotlyjs_name

BUNDLE_HEAD = get_plotlyjs()[:200]     # the start of plotly.min.js, to find an inlined copy


def _report(title):
    rep = Report(title, "a figure and a table")
    rep.figure(go.Figure(go.Scatter(x=[0, 1, 2], y=[2, 0, 1], mode="lines+markers")), div_id="fig")
    rep.table([["a", 1.0]], ["name", "value"])
    return rep


def test_reports_of_one_folder_share_one_plotly_file(tmp_path):
    a = _report("first").write(tmp_path / "a.html")
    b = _report("second").write(tmp_path / "b.html")
    js = sorted(tmp_path.glob("plotly-*.min.js"))
    assert [p.name for p in js] == [plotlyjs_name()]
    assert js[0].read_text(encoding="utf-8") == get_plotlyjs()
    for page in (a, b):
        text = page.read_text(encoding="utf-8")
        assert BUNDLE_HEAD not in text and len(text) < 100_000      # was 4.8 MB per page
        assert f'src="{plotlyjs_name()}"' in text
        assert not re.search(r'<script[^>]+src=["\'](https?:)?//', text), "no script from the network"


def test_inline_plotly_is_one_self_contained_file(tmp_path):
    page = _report("alone").write(tmp_path / "alone.html", inline_plotly=True)
    text = page.read_text(encoding="utf-8")
    assert BUNDLE_HEAD in text and "<script type=\"text/javascript\" src=" not in text
    assert not list(tmp_path.glob("plotly-*.min.js"))


def test_report_draws_offline_in_headless_chromium(tmp_path, chromium):
    """The page loads plotly.js from the file beside it (file://, no network) and draws the figure."""
    require_chromium()
    page_path = _report("offline").write(tmp_path / "report.html")
    page = chromium.open(page_path)
    page.wait_for("typeof Plotly === 'object' && document.querySelector('#fig .main-svg') !== null")
    assert page.evaluate("document.querySelectorAll('#fig .scatterlayer .trace').length") == 1
    urls = page.evaluate("Array.from(document.scripts).filter(function(s){return s.src;}).map(function(s){return s.src;})")
    assert urls == [(tmp_path / plotlyjs_name()).resolve().as_uri()], urls
