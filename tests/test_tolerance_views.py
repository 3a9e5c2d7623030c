"""One truth per page (issue 34 item 4): the JSON's zones, the page's tolerance table, the terminal,
the CSV and the workbook give the same zone for every tolerance -- symmetric, one-sided (+0/−t) and
unequal (+1.6t/−0.4t) -- and the page never shows a one-sided zone as ±t."""
from __future__ import annotations

import contextlib
import html
import io
import json
import re

import pandas as pd
import pytest

from evotol.cli import main
from evotol.studyfile import run_study_file
from evotol.summaries.drawing import tolerance_zone

STUDY = '''name = "views"
seed = 0
[robot]
assembly = "h34_views_gap:gap"
nominal = { a = 0.05, b = 0.02, c = 0.01 }
limits = { gap = 1e-4 }
[bounds]
lower = 1e-6
upper = 1e-3
[cost.default]
model = "power"
a0 = 1.0
a1 = 1.0
scale = 1e-3
[sources.a]
minus = 1.0
plus = 0.0
[sources.b]
minus = 0.4
plus = 1.6
[methods]
optimum = {}
sensitivity = {}
[verify]
n_samples = 50
[report]
units = "mm"
'''


def _cell_numbers(text: str) -> tuple[float, float]:
    """(lower, upper) from a page cell ``±x``, ``+u / −l``, ``0 / −l``."""
    text = text.replace("−", "-")
    if text.startswith("±"):
        v = float(text[1:])
        return -v, v
    up, lo = (p.strip() for p in text.split("/"))
    return float(lo), float(up)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("views")
    (d / "h34_views_gap.py").write_text("def gap(a, b, c):\n    return a - b + c\n")
    (d / "views.toml").write_text(STUDY)
    terminal = io.StringIO()
    with contextlib.redirect_stdout(terminal):          # `evotol run`, as a user types it
        assert main(["run", str(d / "views.toml"), "--out", str(d)]) == 0
    (d / "terminal.txt").write_text(terminal.getvalue())
    return d, json.loads((d / "views.json").read_text())


def _page_cells(d) -> tuple[list[str], dict]:
    """The page's tolerance table: its header and its rows by source (text, unescaped)."""
    page = (d / "views.html").read_text()
    table = page[re.search(r"id=['\"]tolerances['\"]", page).start():]
    table = table[:table.index("</table>")]
    head = [html.unescape(h) for h in re.findall(r"<th>(.*?)</th>", table)]
    return head, {r[0]: r for r in ([html.unescape(c) for c in re.findall(r"<td>(.*?)</td>", row)]
                                    for row in table.split("<tr>")[2:])}


def _terminal_table(d) -> tuple[list[str], dict]:
    """The terminal's tolerance table: its header and its rows by source (columns: 2+ spaces)."""
    lines = (d / "terminal.txt").read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("[evotol] tolerances"))
    head = re.split(r"\s{2,}", lines[i + 1].strip())
    rows = {}
    for line in lines[i + 2:]:
        if not line.startswith("  "):
            break
        cells = re.split(r"\s{2,}", line.strip())
        rows[cells[0]] = cells
    return head, rows


def test_json_csv_xlsx_and_page_show_one_zone(run):
    d, data = run
    src = {s["name"]: s for s in data["sources"]}
    csv = pd.read_csv(d / "views_tolerances.csv", keep_default_na=False).set_index("source")
    book = pd.read_excel(d / "views_tolerances.xlsx", sheet_name=None)
    head, cells = _page_cells(d)
    method = "optimum"
    r = data["results"][method]
    col = head.index(method)
    sheet = book[method].set_index("source")
    for n, s in src.items():
        z = tolerance_zone(s, r["tolerances"][n])
        assert r["zones"][n] == pytest.approx(z, rel=1e-15)                          # JSON
        for table_ in (csv, sheet):                                                   # CSV, XLSX (mm)
            assert table_.loc[n, "lower deviation"] == pytest.approx(z["lower"] * 1e3, rel=1e-12, abs=1e-15)
            assert table_.loc[n, "upper deviation"] == pytest.approx(z["upper"] * 1e3, rel=1e-12, abs=1e-15)
            assert table_.loc[n, "± tolerance"] == pytest.approx(z["half_width"] * 1e3, rel=1e-12)
        lo, up = _cell_numbers(cells[n][col])                                         # page (4 digits)
        assert lo == pytest.approx(z["lower"] * 1e3, rel=1e-3, abs=1e-12)
        assert up == pytest.approx(z["upper"] * 1e3, rel=1e-3, abs=1e-12)
    t = r["tolerances"]["a"]
    assert cells["a"][col].startswith("0 / −")                                       # one-sided, not "± t"
    assert csv.loc["a", "± tolerance"] == pytest.approx(t * 1e3 / 2)
    assert cells["c"][col].startswith("±")
    assert cells["b"][col].startswith("+")


@pytest.mark.parametrize("method", ["optimum", "sensitivity"])
def test_terminal_shows_the_page_zones_and_the_csv_cost_shares(run, method):
    """`evotol run` prints one line per source: the page's zone cell (one function) and the cost
    share of the CSV; the zone's numbers are those of tolerance_zone in the display unit (mm),
    one-sided a (+0/−t), unequal b (+1.6t/−0.4t), symmetric c."""
    d, data = run
    head, cells = _page_cells(d)
    thead, trows = _terminal_table(d)
    assert thead[:2] == ["source", "unit"] and method in thead
    book = pd.read_excel(d / "views_tolerances.xlsx", sheet_name=method).set_index("source")
    r = data["results"][method]
    assert set(trows) == {s["name"] for s in data["sources"]}
    for s in data["sources"]:
        n = s["name"]
        cell = trows[n][thead.index(method)]
        zone, share = re.fullmatch(r"(.*) \(([0-9.]+) %\)", cell).groups()
        assert trows[n][1] == "mm"
        assert zone == cells[n][head.index(method)]                                   # the page's very cell
        z = tolerance_zone(s, r["tolerances"][n])
        lo, up = _cell_numbers(zone)                                                  # its numbers (4 digits)
        assert lo == pytest.approx(z["lower"] * 1e3, rel=1e-3, abs=1e-12)
        assert up == pytest.approx(z["upper"] * 1e3, rel=1e-3, abs=1e-12)
        assert float(share) == pytest.approx(book.loc[n, "cost share (%)"], abs=0.051)   # the workbook's share
    assert trows["a"][thead.index(method)].startswith("0 / −")                        # one-sided
    assert re.match(r"\+[0-9.]+ / −[0-9.]+ ", trows["b"][thead.index(method)])          # unequal
    assert trows["c"][thead.index(method)].startswith("±")
    total = sum(float(re.search(r"\(([0-9.]+) %\)", trows[n][thead.index(method)]).group(1)) for n in trows)
    assert total == pytest.approx(100, abs=0.15)


def test_page_states_the_zone_convention(run):
    d, _ = run
    page = (d / "views.html").read_text()
    assert "deviations from the nominal, ±t when symmetric, +upper / −lower otherwise" in page


@pytest.mark.parametrize("dist, stated", [("uniform", True), ("normal", False)])
def test_rss_verdict_and_monte_carlo_state_their_models(tmp_path, dist, stated):
    """RSS measure (t = 3σ normal): with uniform sources the page says in one line that the Monte
    Carlo samples another model; with normal t = 3σ sources it does not need to."""
    (tmp_path / "h34_views_rss.py").write_text("def gap(a, b, c):\n    return a - b + c\n")
    text = STUDY.replace("h34_views_gap", "h34_views_rss").replace('name = "views"', 'name = "rss"')
    text = text[:text.index("[sources.a]")] + text[text.index("[methods]"):]
    text = text.replace("seed = 0\n", f'seed = 0\ndistribution = "{dist}"\n')
    text = text.replace("[robot]", '[requirement]\nmeasure = "rss"\n[robot]').replace("sensitivity = {}\n", "")
    (tmp_path / "rss.toml").write_text(text)
    run_study_file(tmp_path / "rss.toml", out=tmp_path)
    page = (tmp_path / "rss.html").read_text()
    assert ("Two models: the RSS verdict takes every tolerance as 3σ of a normal" in page) is stated


def test_an_assembly_is_reported_by_its_responses(run):
    """An assembly's page names its response and limit, not a robot's pose and position (issue 34)."""
    d, data = run
    page = html.unescape((d / "views.html").read_text())
    assert data["assembly"] == {"responses": ["gap"], "limits": [1e-4]}
    assert "gap within ±0.0001000 of its nominal" in page and "#0: gap" in page and "× limit" in page
    assert "response = 0" not in page and "max position error" not in page


def _normal_outside(mu: float, sigma: float, limit: float) -> float:
    """P(|gap| > limit) for gap ~ N(mu, sigma²): Φ((−L − μ)/σ) + Φ((μ − L)/σ) (closed form)."""
    from scipy.stats import norm
    return float(norm.cdf((-limit - mu) / sigma) + norm.cdf((mu - limit) / sigma))


def _gap_moments(t: dict) -> tuple[float, float]:
    """Mean and σ of gap = a − b + c under the RSS model (normal about each zone's centre, σ =
    half-width/3): a on [−t, 0], b on [−0.4t, 1.6t], c on [−t, t] (STUDY's zones)."""
    mu = -0.5 * t["a"] - 0.6 * t["b"]
    sigma = ((0.5 * t["a"] / 3) ** 2 + (t["b"] / 3) ** 2 + (t["c"] / 3) ** 2) ** 0.5
    return mu, sigma


@pytest.mark.parametrize("scale", [0.8, 1.0, 1.4])
def test_verify_samples_the_rss_model_when_told(scale):
    """verify(distribution=normal, t = 3σ) on a linear stack: the exceed rate is the exact normal
    P(|gap| > L) within 4 binomial σ (Latin hypercube only narrows it); without the option the
    same problem samples its sources' own (uniform) distributions, another number."""
    from evotol.cost_models import PowerCost
    from evotol import Distribution, LinearStack, Tolerance, assembly_problem, verify
    L = 1e-4
    stack = LinearStack({"a": 1.0, "b": -1.0, "c": 1.0}, {"gap": L})
    shape = {"a": {"minus": 1.0, "plus": 0.0}, "b": {"minus": 0.4, "plus": 1.6}, "c": {}}
    tol = {n: Tolerance(PowerCost(1.0, 1.0, scale=1e-3), lower=1e-7, upper=1e-3, **shape[n]) for n in "abc"}
    problem = assembly_problem(stack, tol)
    t = {"a": 6e-5 * scale, "b": 4e-5 * scale, "c": 5e-5 * scale}
    n = 40000
    mc = verify(problem, t, n_samples=n, seed=3, distribution=Distribution("normal", sigma_k=3.0))
    p = _normal_outside(*_gap_moments(t), L)
    rate = float(mc.exceed_rate["position"][0])
    assert abs(rate - p) <= 4 * (p * (1 - p) / n) ** 0.5 + 1 / n
    assert mc.to_dict()["sampled_distribution"] == {"kind": "normal", "sigma_k": 3.0, "mean_shift": 0.0}
    own = verify(problem, t, n_samples=n, seed=3)                # uniform sources: not the normal figure
    assert "sampled_distribution" not in own.to_dict()
    assert abs(float(own.exceed_rate["position"][0]) - p) > 8 * (p * (1 - p) / n) ** 0.5


def test_an_rss_study_checks_its_verdict_on_the_rss_model(tmp_path):
    """A study file with an rss requirement and no stated distribution: its Monte Carlo samples the
    normal t = 3σ model (the JSON says so, the page says so in one line) and its exceed rate is the
    exact normal probability of the allocated design; the worst-case study beside it samples its
    sources' own distributions as before (no sampled_distribution)."""
    (tmp_path / "h34_views_exact.py").write_text("def gap(a, b, c):\n    return a - b + c\n")
    text = STUDY.replace("h34_views_gap", "h34_views_exact").replace('name = "views"', 'name = "exact"')
    text = text.replace("[robot]", '[requirement]\nmeasure = "rss"\n[robot]').replace("optimum = {}\n", "")
    text = text.replace("n_samples = 50", "n_samples = 40000")
    (tmp_path / "exact.toml").write_text(text)
    run_study_file(tmp_path / "exact.toml", out=tmp_path)
    data = json.loads((tmp_path / "exact.json").read_text())
    mc = data["monte_carlo"]["sensitivity"]
    assert mc["sampled_distribution"] == {"kind": "normal", "sigma_k": 3.0, "mean_shift": 0.0}
    t = data["results"]["sensitivity"]["tolerances"]
    p, n = _normal_outside(*_gap_moments(t), 1e-4), 40000
    assert abs(mc["max_exceed_rate"] - p) <= 4 * (p * (1 - p) / n) ** 0.5 + 1 / n
    page = html.unescape((tmp_path / "exact.html").read_text())
    assert "The Monte Carlo sampled every source from one model: normal (t = 3σ) about its zone's centre" in page
    assert "the RSS verdict's own model" in page and "Two models" not in page


def test_a_worst_case_study_samples_the_sources_own_distributions(run):
    d, data = run
    assert all("sampled_distribution" not in c for c in data["monte_carlo"].values())
    assert "The Monte Carlo sampled each source's own distribution (uniform)." in html.unescape((d / "views.html").read_text())


def test_a_bad_verify_distribution_is_refused_before_any_method(tmp_path, capsys):
    """[verify] distribution = "gauss": one line naming the field, nothing run, nothing written."""
    (tmp_path / "h34_views_bad.py").write_text("def gap(a, b, c):\n    return a - b + c\n")
    text = STUDY.replace("h34_views_gap", "h34_views_bad").replace('name = "views"', 'name = "bad"')
    (tmp_path / "bad.toml").write_text(text.replace("n_samples = 50", 'n_samples = 50\ndistribution = "gauss"'))
    assert main(["run", str(tmp_path / "bad.toml"), "--out", str(tmp_path)]) == 2
    out = capsys.readouterr()
    assert "verify.distribution" in out.err and "gauss" in out.err and "[evotol] optimum" not in out.out
    assert not (tmp_path / "bad.json").exists()


def test_a_stack_allocation_prints_the_page_drawn_zones(tmp_path):
    """The shipped motor stack (reports/studies/motor_stack.toml, [stack.allocation]): the terminal's
    drawn zone and cost share per dimension are the page's allocation cells, and each zone's numbers
    are the JSON's drawn zone (inches)."""
    from pathlib import Path
    study = Path(__file__).resolve().parents[1] / "reports" / "studies" / "motor_stack.toml"
    terminal = io.StringIO()
    with contextlib.redirect_stdout(terminal):
        assert main(["run", str(study), "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "motor_stack.json").read_text())
    page = (tmp_path / "motor_stack.html").read_text()
    table = page[re.search(r"id=['\"]allocation['\"]", page).start():]
    table = table[:table.index("</table>")]
    cells = {r[0]: r for r in ([html.unescape(c) for c in re.findall(r"<td>(.*?)</td>", row)]
                               for row in table.split("<tr>")[2:])}
    lines = terminal.getvalue().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("[evotol] allocated zones"))
    names = [d["name"] for d in data["stack"]["dimensions"]]
    rows = {c[0]: c for c in (re.split(r"\s{2,}", line.strip()) for line in lines[i + 2:i + 2 + len(names)])}
    methods = list(data["allocation"]["methods"])
    assert set(rows) == set(names) and len(methods) >= 2
    for n in names:
        assert rows[n] == cells[n]                                            # the page's very cells
        for k, m in enumerate(methods):
            z = data["allocation"]["methods"][m]["drawing"]["zones"][n]
            up, lo = (float(v.replace("−", "-")) for v in rows[n][1 + k].split(" (")[0].split(" / "))
            assert (lo, up) == pytest.approx((z["drawing_lower"], z["drawing_upper"]), abs=5e-5)
