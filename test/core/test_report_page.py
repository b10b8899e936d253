"""The report reads as an answer followed by its evidence: structure of the page `cablelab report`
writes (parsed with the standard library's HTML parser), the ranking's statistics agreeing with its
significance column, units in every header, gaps drawn as gaps, every figure captioned."""
from __future__ import annotations

import re
from html.parser import HTMLParser

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cablelab.diagnose.ranking import ALPHA, MIN_GAIN
from cablelab.diagnose.result import Candidate, Step
from cablelab.report.sections import metrics_table, ranking_section
from cablelab.report.plots import _thin_masked, invalid_spans

from robust_helpers import CDPR


class Page(HTMLParser):
    """Headings (in order), tables (header + rows of cell texts), figures (img src, caption)."""

    def __init__(self, text: str):
        super().__init__()
        self.headings, self.tables, self.figures, self.loose_images = [], [], [], []
        self._tag_text = None
        self._cell = None
        self._row = None
        self._figure = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag in ("h1", "h2", "h3"):
            self._tag_text = [tag, ""]
        elif tag == "table":
            self.tables.append({"header": [], "rows": []})
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = ""
        elif tag == "figure":
            self._figure = {"src": None, "caption": ""}
        elif tag == "figcaption" and self._figure is not None:
            self._figure["in_caption"] = True
        elif tag == "img":
            if self._figure is not None:
                self._figure["src"] = a.get("src")
            else:
                self.loose_images.append(a.get("src"))

    def handle_endtag(self, tag):
        if tag in ("h1", "h2", "h3") and self._tag_text:
            self.headings.append(self._tag_text[1].strip())
            self._tag_text = None
        elif tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell.strip())
            kind = "header" if tag == "th" else None
            self._cell = None
            if kind:
                self.tables[-1]["_th"] = True
        elif tag == "tr" and self._row is not None:
            t = self.tables[-1]
            if t.pop("_th", False):
                t["header"] = self._row
            else:
                t["rows"].append(self._row)
            self._row = None
        elif tag == "figcaption" and self._figure is not None:
            self._figure.pop("in_caption", None)
        elif tag == "figure" and self._figure is not None:
            self.figures.append(self._figure)
            self._figure = None

    def handle_data(self, data):
        if self._tag_text is not None:
            self._tag_text[1] += data
        if self._cell is not None:
            self._cell += data
        if self._figure is not None and self._figure.get("in_caption"):
            self._figure["caption"] += data

    def table_with(self, column: str) -> dict:
        return next(t for t in self.tables if column in t["header"])

    def tables_with(self, column: str) -> list[dict]:
        return [t for t in self.tables if column in t["header"]]


def _pct(cell: str) -> float | None:
    return None if cell.strip() == "-" else float(cell.replace("%", "").strip())


def _p(cell: str) -> float | None:
    cell = cell.strip()
    if cell == "-":
        return None
    return 0.0 if cell.startswith("<") else float(cell)


def check_ranking_rows(table: dict, baseline_percent: float) -> int:
    """Every row of one ranking table: 'significant' is yes exactly when the displayed held-out
    gain, held-out NRMSE, p and identifiability meet the thresholds the table's headers state; a
    'no' names a criterion the displayed numbers really fail. Returns the number of rows checked."""
    h = table["header"]
    gain_col = next(i for i, x in enumerate(h) if x.startswith("held-out gain"))
    p_col = next(i for i, x in enumerate(h) if x.startswith("p, "))
    min_gain = float(re.search(r"significant from ([0-9.]+) %", h[gain_col]).group(1))
    threshold = float(re.search(r"significant below ([0-9.e-]+)\)", h[p_col]).group(1))
    col = {name: h.index(name) for name in ("held-out NRMSE with it", "identifiable", "significant")}
    for row in table["rows"]:
        err = _pct(row[col["held-out NRMSE with it"]])
        gain = _pct(row[gain_col])
        p = _p(row[p_col])
        ident = row[col["identifiable"]]
        sig_cell = row[col["significant"]]
        expected = (err is not None and gain is not None and p is not None
                    and gain >= min_gain - 0.05             # the gain is shown to 0.1 %
                    and err < baseline_percent + 0.005 and p < threshold and ident != "no")
        assert sig_cell.startswith("yes" if expected else "no"), (row, threshold)
        if sig_cell.startswith("no") and err is not None:
            assert "gain below" in sig_cell and gain < min_gain + 0.05 \
                or "does not fall" in sig_cell and err >= baseline_percent - 0.005 \
                or "p not below" in sig_cell and p >= threshold * 0.95 \
                or "not identifiable" in sig_cell and ident == "no", row
    return len(table["rows"])


# ------------------------------------------------------------------------ the ranking, unit level
def _row(effect, after, gain, p, identifiable=True, before=0.20):
    sig = (gain >= MIN_GAIN and after < before and p < ALPHA / 4 and identifiable)
    return Candidate(effect, before, after, gain=gain, p_value=p, significant=sig,
                     explanation=f"{effect} ...",
                     identifiability={"identifiable": identifiable, "confounded": []})


def _step(ranking, error, effects):
    return Step(effects=effects, added=None, error=error, params={}, stderr={}, units={},
                ranking=ranking)


def test_ranking_shows_the_decisive_quantity_beside_every_decision():
    """The case of the probe: a vanishing in-sample p next to 'significant: no' (gain 3 %) now
    stands beside the held-out gain that decides it, and the reason says so."""
    rows = [_row("a", 0.10, 0.50, 1e-40),
            _row("tiny_p_small_gain", 0.194, 0.03, 6.5e-124),
            _row("big_gain_but_confounded", 0.12, 0.40, 1e-30, identifiable=False),
            _row("gain_but_p_large", 0.15, 0.25, 0.2)]
    rows.append(Candidate("unfittable", 0.2, None, explanation="unfittable: cannot be fitted (rank)"))
    page = Page(ranking_section([_step(rows, 0.20, ["m"])]))
    assert check_ranking_rows(page.table_with("significant"), 20.0) == 5
    t = page.table_with("significant")
    sig = {r[0]: r[t["header"].index("significant")] for r in t["rows"]}
    assert sig["a"].startswith("yes")
    assert sig["tiny_p_small_gain"] == "no (held-out gain below 5 %)"
    assert sig["big_gain_but_confounded"].startswith("no (not identifiable")
    assert sig["gain_but_p_large"].startswith("no (p not below")
    assert sig["unfittable"].startswith("no (cannot be fitted")


def test_ranking_consistency_check_catches_a_contradiction():
    """The checker itself fails on the page the probe saw (p tiny, gain large, 'no' without a
    reason the numbers show)."""
    row = _row("x", 0.10, 0.50, 1e-124)
    row.significant = False           # the diagnosis said no for a reason the page cannot show
    step = _step([row], 0.20, [])
    page = Page(ranking_section([step]).replace("see the explanation", "held-out gain below 5 %"))
    with pytest.raises(AssertionError):
        check_ranking_rows(page.table_with("significant"), 20.0)


def test_metrics_headers_carry_the_real_unit():
    met = [{"nrmse": 0.1, "fit_percent": 90.0, "pearson": 0.99, "mae": 1.5, "mre": 0.01, "max_abs": 4.0}] * 2
    same = Page(metrics_table(["Fx", "Fy"], ["N", "N"], met, met)).tables[0]
    assert "MAE final [N]" in same["header"] and "max abs final [N]" in same["header"]
    mixed = Page(metrics_table(["Fx", "Mx"], ["N", "N m"], met, met)).tables[0]
    mae = mixed["header"].index("MAE final")
    assert [r[mae] for r in mixed["rows"]] == ["1.5 N", "1.5 N m"]
    for t in (same, mixed):
        assert not any("[unit]" in h and h != "channel [unit]" for h in t["header"]), t["header"]


# ---------------------------------------------------------------------------------------- gaps
@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 20000), runs=st.lists(st.tuples(st.integers(0, 19999), st.integers(1, 30)),
                                              max_size=6))
def test_gaps_break_the_line_and_are_shaded(n, runs):
    """Every invalid sample lies inside a shaded span, every span holds only invalid samples, and
    the drawn (thinned) line is NaN wherever its thinning window holds an invalid sample."""
    t = 0.01 * np.arange(n)
    valid = np.ones(n, bool)
    for a, k in runs:
        valid[a % n:(a % n) + k] = False
    spans = invalid_spans(t, valid)
    inside = np.zeros(n, bool)
    for lo, hi in spans:
        inside |= (t > lo) & (t < hi)
    assert np.array_equal(inside, ~valid)
    y = np.column_stack([np.sin(t), np.cos(t)])
    tt, yy = _thin_masked(t, y, valid)
    step = max(1, n // 4000)
    for j, t0 in enumerate(tt):
        i = j * step
        window_ok = valid[i:i + step].all()
        assert np.isnan(yy[j]).all() != window_ok
        assert t0 == t[i]


# ------------------------------------------------------------------------ a real report, end to end
@pytest.fixture(scope="module")
def cdpr_report(tmp_path_factory):
    """The report of the CDPR reference bag (its waterfall finds platform_inertia; its ranking
    holds candidates with a tiny p that are not significant)."""
    from cablelab.cli import main

    out = tmp_path_factory.mktemp("report") / "rep"
    assert main(["report", str(CDPR), "-o", str(out), "--folds", "3", "--json"]) == 0
    return out


def test_report_leads_with_the_answer_then_the_evidence(cdpr_report):
    page = Page((cdpr_report / "index.html").read_text())
    h = page.headings
    answer = next(i for i, x in enumerate(h) if x.startswith("Answer"))
    ranking = next(i for i, x in enumerate(h) if x.startswith("Ranking"))
    evidence = next(i for i, x in enumerate(h) if x.startswith("Evidence"))
    regimes = h.index("Residual by operating regime")
    assert answer < ranking < evidence < regimes, h
    srcs = [f["src"] for f in page.figures]
    assert srcs[0] == "waterfall.png"
    # no residual plot before the ranking: the first figures are the waterfall and the overlay
    assert srcs.index("overlay.png") < min(i for i, s in enumerate(srcs) if "residual" in s)
    text = (cdpr_report / "index.html").read_text()
    assert text.index("platform_inertia") < text.index("residual_time.png")


def test_report_ranking_agrees_with_its_significance_column(cdpr_report):
    """Every ranking (nominal model, then after each greedy step): the statistics shown agree
    with the significance column; the steps' rankings add exactly the waterfall's effects."""
    page = Page((cdpr_report / "index.html").read_text())
    steps = page.table_with("held-out NRMSE")                 # the waterfall's table of steps
    errors = [_pct(r[steps["header"].index("held-out NRMSE")]) for r in steps["rows"]]
    tables = page.tables_with("significant")
    assert len(tables) == len(errors) >= 2
    for table, base in zip(tables, errors):
        assert check_ranking_rows(table, base) >= 3
    sig = [[r[0] for r in t["rows"] if r[t["header"].index("significant")].startswith("yes")] for t in tables]
    assert sig[0][0] == "platform_inertia" == steps["rows"][1][1] and sig[-1] == []


def test_report_every_figure_captioned_and_units_in_headers(cdpr_report):
    page = Page((cdpr_report / "index.html").read_text())
    assert not page.loose_images
    assert len(page.figures) >= 10
    for f in page.figures:
        assert f["src"] and (cdpr_report / f["src"]).is_file(), f
        assert len(f["caption"].split()) >= 5, f
    regimes = [f for f in page.figures if f["src"].startswith("regimes_")]
    assert len(regimes) == 6 and all(re.search(r"\([0-9.]+ (N|N m)\)", f["caption"]) for f in regimes)
    for t in page.tables:
        for head in t["header"]:
            assert "[unit]" not in head or head == "channel [unit]", head
    t = page.table_with("MAE final")
    col = t["header"].index("MAE final")
    assert all(re.fullmatch(r"[-0-9.e+]+ (N|N m)", r[col]) for r in t["rows"]), t["rows"]
    # the CDPR bag has holes: the overlay's caption says how many samples are shaded
    overlay = next(f for f in page.figures if f["src"] == "overlay.png")
    assert re.search(r"Grey bands: \d+ samples", overlay["caption"])


def test_report_evidence_points_at_the_missing_effect(cdpr_report):
    """The CDPR bag lacks the platform's inertia m a, a vertical force while the platform
    accelerates vertically: the shaded worst windows and the worst regime of Fz say so (and not
    the noisiest channel), and no figure repeats another."""
    import hashlib

    page = Page((cdpr_report / "index.html").read_text())
    segs = page.table_with("residual RMS in the window")
    assert segs["rows"] and {r[0] for r in segs["rows"]} == {"Fz"}, segs["rows"]
    regimes = page.table_with("regime")
    fz = next(r for r in regimes["rows"] if r[0] == "Fz")
    assert "vertical" in fz[1], fz
    assert _pct(fz[-1]) < _pct(fz[-2]) / 3          # the final model removes most of it
    digests = [hashlib.sha256((cdpr_report / f["src"]).read_bytes()).hexdigest() for f in page.figures]
    assert len(set(digests)) == len(digests)
