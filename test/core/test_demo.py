"""The demo's crane helpers against MuJoCo, and the combined index page."""
from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.optimize import root

from cablelab.description import load_description
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.mjcf import build_mjcf
from cablelab.plants.crane.sim import CraneTruth, gravity_in_base, set_state
from cablelab import demo
from cablelab.plants.crane import demo as demo_crane


@pytest.fixture(scope="module")
def params():
    import cablelab

    desc = load_description(str(__import__("pathlib").Path(cablelab.__file__).parent / "plants" / "crane" / "data" / "crane.yaml"))
    return CraneParams.from_description(desc)


def slew_torque_at_rest(truth: CraneTruth, alpha: float, beta: float, d: float = 0.6) -> float:
    """Slew torque (N m) that holds the MuJoCo crane at rest with the payload hanging in its
    equilibrium (zero generalised force on both swing joints, found numerically)."""
    model = build_mjcf(truth)
    data = mujoco.MjData(model)

    def state(sw):
        set_state(model, data, [alpha, beta, d, sw[0], sw[1]])
        return data.qfrc_bias.copy()

    sw = root(lambda s: state(s)[2:4], [0.0, 0.0], tol=1e-14).x
    bias = state(sw)
    assert np.abs(bias[2:4]).max() < 1e-10          # really the equilibrium
    return float(bias[0])


def test_tilt_for_rest_torque_gives_002_offset_in_mujoco(params):
    """002 sec. 6.5: the hidden tilt the demo gives the simulator loads the slew joint with -0.2 N m
    at rest at beta = 0.5 rad (MuJoCo's bias force as the independent oracle)."""
    tilt = demo_crane.tilt_for_rest_torque(params.first_moment, params.gravity)
    assert 0.02 < abs(tilt) < 0.1                    # a few degrees, like a non-rigid base
    truth = CraneTruth(params=params, base_tilt=(tilt, 0.0))
    assert slew_torque_at_rest(truth, 0.0, demo_crane.REST_LUFF) == pytest.approx(-0.2, abs=1e-9)
    # an untilted base needs no slew torque at rest
    assert abs(slew_torque_at_rest(CraneTruth(params=params), 0.4, 0.5)) < 1e-12


@pytest.mark.parametrize("alpha,beta", [(0.0, 0.5), (0.7, 0.3), (-2.0, -0.2)])
def test_rest_torque_of_fitted_tilt_matches_mujoco(params, alpha, beta):
    """The rest torque the demo reads off the fitted base_tilt angles (tilt_x = -g_y / g,
    tilt_y = g_x / g) equals the torque MuJoCo needs to hold the tilted crane, for a tilt about
    both axes and any pose."""
    truth = CraneTruth(params=params, base_tilt=(-0.04, 0.03))
    g = gravity_in_base(truth)
    fitted = {"tilt_x": -g[1] / params.gravity, "tilt_y": g[0] / params.gravity}
    assert demo_crane.rest_torque(fitted, params.first_moment, params.gravity, alpha, beta) == pytest.approx(
        slew_torque_at_rest(truth, alpha, beta), abs=1e-9)


class _Links(__import__("html.parser").parser.HTMLParser):
    """``[(href, text)]`` of every link of a page."""

    def __init__(self, text):
        super().__init__()
        self.links, self._href = [], None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        if tag == "a":
            self._href, self._text = dict(attrs)["href"], ""

    def handle_data(self, data):
        if self._href is not None:
            self._text += data

    def handle_endtag(self, tag):
        if tag == "a" and self._href is not None:
            self.links.append((self._href, self._text.strip()))
            self._href = None


def check_index_links(index) -> list[tuple[str, str]]:
    """Every link of the demo index opens what its text names: 'demo page' an HTML page,
    'diagnosis report' a `cablelab report` page (its own title) other than any demo page, 'bag X'
    the bag directory X holding its .mcap. Returns the links."""
    from pathlib import Path

    index = Path(index)
    links = _Links(index.read_text()).links
    assert links
    pages = set()
    for href, text in links:
        target = (index.parent / href).resolve()
        if text == "demo page":
            assert target.suffix == ".html" and target.is_file(), (href, text)
            pages.add(target)
        elif text == "diagnosis report":
            assert target.suffix == ".html" and target.is_file(), (href, text)
            assert "<title>cablelab report</title>" in target.read_text(), (href, text)
        elif text.startswith("bag "):
            assert target.is_dir() and (index.parent / text[4:]).resolve() == target, (href, text)
            assert list(target.glob("*.mcap")), (href, text)
        else:
            raise AssertionError(f"link {text!r} ({href}) names no known kind")
    reports = {(index.parent / h).resolve() for h, t in links if t == "diagnosis report"}
    assert not reports & pages
    return links


def _bag(path):
    path.mkdir(parents=True)
    (path / f"{path.name}.mcap").write_bytes(b"")
    return path


def test_index_page_links_go_where_they_say(tmp_path):
    """Parts like the plants' own: a real report beside the page (cdpr, crane), a page that is
    also passed as the report (suspended), a PNG passed as the report (leg), a report that was
    never written: the index links each page, only real reports, and each bag."""
    from pathlib import Path

    report_html = "<!DOCTYPE html><html><head><title>cablelab report</title></head><body></body></html>"
    parts = {}
    for name in ("cdpr", "crane"):
        (tmp_path / name / "report").mkdir(parents=True)
        (tmp_path / name / "report" / "index.html").write_text(report_html)
        (tmp_path / name / "report" / "page.html").write_text("<html></html>")
        parts[f"{name} <plant>"] = demo.PartResult(rows=[["q & a", "1.0", "2.0"]],
                                                   bags=[_bag(tmp_path / name / "run")],
                                                   report=str(tmp_path / name / "report" / "index.html"),
                                                   page=str(tmp_path / name / "report" / "page.html"))
    (tmp_path / "suspended.html").write_text("<html></html>")
    parts["suspended"] = demo.PartResult(bags=[_bag(tmp_path / "susp_bag")], report=str(tmp_path / "suspended.html"),
                                         page=str(tmp_path / "suspended.html"))
    (tmp_path / "leg.html").write_text("<html></html>")
    (tmp_path / "leg_demo.png").write_bytes(b"\x89PNG")
    parts["leg"] = demo.PartResult(bags=[_bag(tmp_path / "leg_bag")], report=str(tmp_path / "leg_demo.png"),
                                   page=str(tmp_path / "leg.html"))
    (tmp_path / "ghost.html").write_text("<html></html>")
    parts["ghost"] = demo.PartResult(report=str(tmp_path / "never" / "index.html"),
                                     page=str(tmp_path / "ghost.html"), bags=[tmp_path / "missing_bag"])
    index = Path(demo.index_page(tmp_path, parts))
    links = check_index_links(index)
    assert sorted(h for h, t in links if t == "diagnosis report") == ["cdpr/report/index.html",
                                                                       "crane/report/index.html"]
    assert sorted(h for h, t in links if t == "demo page") == sorted(
        ["cdpr/report/page.html", "crane/report/page.html", "suspended.html", "leg.html", "ghost.html"])
    assert len([t for _, t in links if t.startswith("bag ")]) == 4
    text = index.read_text()
    assert "&lt;plant&gt;" in text and "q &amp; a" in text      # escaped, relative links


def test_index_link_checker_catches_a_png_called_report(tmp_path):
    (tmp_path / "p.png").write_bytes(b"")
    (tmp_path / "index.html").write_text("<a href='p.png'>diagnosis report</a>")
    with pytest.raises(AssertionError):
        check_index_links(tmp_path / "index.html")


def test_leg_and_suspended_parts_name_no_report_they_do_not_write(tmp_path):
    """The leg part (a plot) and the suspended part (one page) write no `cablelab report`: their
    results say so, and the index links only their pages and bags."""
    from pathlib import Path

    from cablelab.plants.leg import demo as leg_demo
    from cablelab.plants.suspended import demo as susp_demo

    leg = leg_demo._analyse(tmp_path, None, {
        "waterfall": [{"step": "nominal", "cv_error": 0.3}, {"step": "+ impact_restitution (x)", "cv_error": 0.1}],
        "identified": {"beta_td": 0.5, "beta_lo": 0.4, "F0": 2.7}, "truth": {"beta_td": 0.5, "beta_lo": 0.4},
        "fig11": {"apex_height_mae_mm": {"with_impact": 1.0, "without_impact": 2.0},
                  "apex_time_mae_ms": {"with_impact": 1.0, "without_impact": 2.0}},
        "bag": str(_bag(tmp_path / "leg_run")), "plot": str(tmp_path / "leg_demo.png")})
    susp = susp_demo._analyse(tmp_path, None, {
        "identification": {"undetermined": []},
        "baselines": [{"max_error_m": 0.01, "rho_r_y": 0.99, "mre_r_y": 0.1},
                      {"model": "pendulum", "reduction_percent": 50.0, "paper_reduction_percent": 60}],
        "diagnosis": {"hidden": "air_drag", "first": "air_drag", "significant": True, "error_before": 0.2,
                      "error_after": 0.1, "bag": str(_bag(tmp_path / "susp_run"))}})
    for part in (leg, susp):
        assert part.report == "" and Path(part.page).suffix == ".html"
    check_index_links(demo.index_page(tmp_path, {"leg": leg, "suspended": susp}))


def test_demo_parts_come_from_the_plant_registry():
    """Every plant with a ``demo`` module brings its part and its options; none is named here."""
    names = [p.plant for p in demo.demo_parts()]
    assert names[:2] == ["cdpr", "crane"]
    from cablelab.registry import available_plants

    assert set(names) <= set(available_plants())
    with pytest.raises(SystemExit):
        demo.main(["--skip-nonexistent"])
