"""The drawing-callout section of reports/studies/ur5_callouts_shop.toml as headless Chromium renders
it with the machine's own fonts (issue 41: "⌖" drew as an empty box where no font had it).

Chromium's ``--dump-dom`` gives the DOM after scripts ran: every frame symbol of the callout table is
an inline SVG named for its characteristic (position, diameter, profile of a surface) and no symbol
is left to a font; through the DevTools protocol the page's own layout is read: each symbol is drawn
at the text's size, and each feature control frame stays on one line (it broke after the ⌀ in a
narrow column). Values are compared with the table's own value column.
"""
from __future__ import annotations

import html as html_lib
import re
import subprocess

import pytest

from evotol.reporting.headless import CHROMIUM_FLAGS
from evotol.studyfile import run_study_file
from tests.browser import require_chromium
from tests.test_shop import STUDY

SYMBOL_GLYPHS = "⌖⌀⌓⊥∥"


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    d = tmp_path_factory.mktemp("callouts")
    text = STUDY.read_text().replace("grid = [3, 3, 3]", "grid = [2, 2, 2]")
    text = text.replace("ga = { pop_size = 80, n_gen = 150 }", "").replace("n_samples = 300", "n_samples = 20")
    (d / "s.toml").write_text(text)
    run_study_file(d / "s.toml", out=d)
    return d / "ur5_callouts_shop.html"


def _callout_rows(dom: str) -> list[list[str]]:
    table = dom[dom.index('id="callouts"'):]
    table = table[:table.index("</table>")]
    return [re.findall(r"<td[^>]*>(.*?)</td>", row, re.S) for row in re.findall(r"<tr>(.*?)</tr>", table, re.S)[1:]]


def test_callout_symbols_are_svg_and_no_glyph_is_left_to_a_font(page):
    chromium = require_chromium()
    dom = subprocess.run([chromium, *CHROMIUM_FLAGS, "--dump-dom", page.as_uri()], capture_output=True, text=True,
                         timeout=180, check=True).stdout
    rows = _callout_rows(dom)
    assert len(rows) == 12                                          # 6 bores + 6 faces of the UR5's seats
    for cells in rows:
        feature, frame, value = html_lib.unescape(cells[1]), cells[2], float(cells[3])
        labels = re.findall(r'<svg class="gdt"[^>]*aria-label="([^"]+)"', frame)
        text = html_lib.unescape(re.sub(r"<title>.*?</title>|<[^>]+>", "", frame))
        if feature.startswith("bore axis"):
            assert labels == ["position", "diameter"], frame
            assert re.fullmatch(r" \| ([\d.]+) µm \| A \| B", text) and float(text.split()[1]) == pytest.approx(value)
        else:
            assert feature.startswith("shoulder face") and labels == ["profile of a surface"], frame
            assert re.fullmatch(r" \| ([\d.]+) µm \| A \| B", text) and float(text.split()[1]) == pytest.approx(value)
        # no symbol glyph, no replacement character, nothing beyond µ outside ASCII: no tofu possible
        assert not set(text) & set(SYMBOL_GLYPHS + "\ufffd") and set(text) - set(map(chr, range(128))) <= {"µ"}
        assert "nan" not in " ".join(cells).lower().split()


def test_each_frame_renders_on_one_line_with_symbols_at_text_size(page, chromium):
    require_chromium()
    tab = chromium.open(page)
    got = tab.evaluate("""(() => [...document.querySelectorAll('#callouts tbody tr, #callouts tr')].filter(
        tr => tr.querySelector('td')).map(tr => {
          const td = tr.querySelectorAll('td')[2];
          const range = document.createRange(); range.selectNodeContents(td);
          const rects = [...range.getClientRects()].filter(r => r.width > 0);
          const top = Math.min(...rects.map(r => r.top)), bottom = Math.max(...rects.map(r => r.bottom));
          const font = parseFloat(getComputedStyle(td).fontSize);
          const svgs = [...td.querySelectorAll('svg.gdt')].map(s => s.getBoundingClientRect());
          return {span: bottom - top, font: font, svgs: svgs.map(r => [r.width, r.height])};
        }))()""")
    assert len(got) == 12
    for row in got:
        assert row["span"] < 1.8 * row["font"], row                  # one line (two would be about 2.8 em)
        assert row["svgs"] and all(0.8 * row["font"] <= w <= 1.2 * row["font"] and 0.8 * row["font"] <= h <= 1.2 * row["font"]
                                   for w, h in row["svgs"]), row
