"""``replay.html`` of real runs, opened in headless Chromium (Debian's ``chromium``, driven by
playwright): what it draws at a step matches the run's files, it plays, and it loads nothing
from the network and logs no error. Without Chromium these tests fail; they never skip."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.reporting.replay import REPLAY, replay_href
from sse_cosim.runner.run import run_scenario_file

pytestmark = [pytest.mark.sumo, pytest.mark.browser]
ROOT = Path(__file__).resolve().parents[2]
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"
S2 = ROOT / "scenarios" / "s2_pedestrian.toml"
JUNCTION = ROOT / "sumo_net" / "junction"  # a four-arm junction with route-file traffic
S3_SECONDS = 12.5  # the pedestrian steps onto the zebra at 11.5 s
PAGE_LIMIT_BYTES_PER_S = 5e6 / 30  # a 30 s run's page stays under 5 MB
class Replay:
    """One replay page open in the browser, with every console error, page error and network
    request it made."""

    def __init__(self, browser, folder: Path, fragment: str = "") -> None:
        self.problems: list[str] = []
        self.page = browser.new_page()
        self.page.on("console", lambda m: m.type == "error" and self.problems.append(m.text))
        self.page.on("pageerror", lambda e: self.problems.append(str(e)))
        self.page.on("request", lambda r: r.url.startswith("file:")
                     or self.problems.append(f"loads {r.url}"))
        self.page.goto((folder / REPLAY).as_uri() + fragment)
        self.page.wait_for_function("window.replay !== undefined")

    def step(self) -> int:
        return self.page.evaluate("replay.current()")

    def time(self) -> float:
        return self.page.evaluate("replay.data.frames[replay.current()].t")

    def level(self, vehicle: str) -> str:
        return self.page.locator(f'.level[data-vehicle="{vehicle}"] .value').inner_text()

    def slide_to(self, step: int) -> None:
        self.page.evaluate("s => { const el = document.getElementById('slider'); el.value = s; "
                           "el.dispatchEvent(new Event('input')); }", step)


@pytest.fixture(scope="module")
def s3_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("s3_replay")
    run_scenario_file(S3, out, {"simulation.duration_s": S3_SECONDS}, plots=False)
    return out


def at(table: pd.DataFrame, t: float) -> pd.DataFrame:
    return table[np.isclose(table["t"], t)]


def test_the_page_opens_at_the_first_detection_unless_its_address_names_a_moment(
        tmp_path, browser):
    """Opened plain, the replay shows the run's key moment (the first detection of
    summary.json, the moment report.html links to with #t=; in S2 the car's at 3.3 s), not the
    bus alone at t = 0; #t=<s> and #step=<n> open it elsewhere."""
    run_scenario_file(S2, tmp_path / "s2", {"simulation.duration_s": 4.0}, plots=False)
    summary = json.loads((tmp_path / "s2" / "summary.json").read_text(encoding="utf-8"))
    first = min(entry["t"] for entry in summary["first_detection"].values())
    assert first > 1.0
    assert Replay(browser, tmp_path / "s2").time() == pytest.approx(first)
    assert Replay(browser, tmp_path / "s2", "#t=2.5").time() == pytest.approx(2.5)
    assert Replay(browser, tmp_path / "s2", "#step=7").step() == 7
    assert replay_href(tmp_path / "s2", tmp_path, summary) == f"s2/{REPLAY}#t={first:g}"


def test_the_page_draws_the_pedestrian_and_shows_the_level_of_the_step(s3_run, browser):
    trace = pd.read_csv(s3_run / "trace.csv")
    truth = pd.read_csv(s3_run / "truth.csv")
    replay = Replay(browser, s3_run, "#step=120")
    assert replay.step() == 120
    truth_now = at(truth, replay.time()).set_index("pedestrian").loc["pedestrian"]
    marker = replay.page.locator('circle.pedestrian[data-id="pedestrian"]')
    # the scene's user space is (x, -y) in m, the stored coordinates are rounded to 1 cm
    assert float(marker.get_attribute("cx")) == pytest.approx(truth_now["x"], abs=0.006)
    assert float(marker.get_attribute("cy")) == pytest.approx(-truth_now["y"], abs=0.006)
    shown, scene = marker.bounding_box(), replay.page.locator("#scene").bounding_box()
    assert scene["x"] < shown["x"] < scene["x"] + scene["width"]
    assert scene["y"] < shown["y"] < scene["y"] + scene["height"]
    level_now = at(trace, replay.time()).set_index("vehicle").loc["bus", "level"]
    assert replay.level("bus") == level_now
    marker.click()
    assert replay.page.inner_text("#info").startswith("pedestrian pedestrian\nposition (")

    replay.slide_to(10)
    assert replay.step() == 10
    level_then = at(trace, replay.time()).set_index("vehicle").loc["bus", "level"]
    assert level_then != level_now  # the bus slows down between the two steps
    assert replay.level("bus") == level_then
    assert replay.problems == []


def test_the_page_plays_and_every_layer_is_drawn(s3_run, browser):
    replay = Replay(browser, s3_run, "#step=120")
    for layer in ("sectors", "shadows", "strips", "vehicles", "local", "fused", "refined",
                  "pedestrians"):
        assert replay.page.locator(f"#layer-{layer} > *").count() > 0, layer
    replay.page.locator("#layer-fused path").dispatch_event("mouseover")
    head, area = replay.page.inner_text("#info").split("\n")
    assert head == "bus's fused set of pedestrian"
    fused_area = at(pd.read_csv(s3_run / "trace.csv"), replay.time())["fused_area"].item()
    assert float(area.removeprefix("area ").removesuffix(" m²")) == pytest.approx(fused_area,
                                                                               rel=0.02)
    replay.page.click("#play")
    replay.page.wait_for_function("replay.current() > 121")
    replay.page.click("#play")
    paused = replay.step()
    replay.page.keyboard.press("ArrowRight")
    assert replay.step() == paused + 1
    assert replay.problems == []


def test_a_page_stays_small(s3_run):
    assert (s3_run / REPLAY).stat().st_size < PAGE_LIMIT_BYTES_PER_S * S3_SECONDS


def test_a_page_with_two_automated_vehicles_shows_both(tmp_path, browser):
    second_bus = {"automated.bus2.depart_s": 3.0, "simulation.duration_s": 5.0}
    run_scenario_file(S3, tmp_path, second_bus, plots=False)
    replay = Replay(browser, tmp_path, "#step=40")
    assert replay.page.locator(".level").count() == 2
    trace = at(pd.read_csv(tmp_path / "trace.csv"), replay.time()).set_index("vehicle")
    assert [replay.level(v) for v in ("bus", "bus2")] == list(trace.loc[["bus", "bus2"], "level"])
    assert replay.page.locator("polyline.speed-line").count() == 2
    replay.page.select_option("#ego", "bus2")
    assert replay.page.locator("#layer-unobserved > *").count() == 1
    assert replay.problems == []


def test_a_page_of_another_network_shows_its_map_and_route_file_traffic(tmp_path, browser):
    junction = {
        "network.sources_dir": str(JUNCTION),
        "network.route_files": [str(JUNCTION / "traffic.rou.xml")],
        "automated.bus.route_edges": ["WJ", "JE"], "automated.bus.depart_pos_m": 30.0,
        "automated.bus.nominal_speed_mps": 13.89, "parked.truck.present": False,
        "pedestrians.pedestrian.start_edge": "WJ", "pedestrians.pedestrian.start_pos_m": 172.0,
        "pedestrians.pedestrian.end_edge": "JW", "pedestrians.pedestrian.end_pos_m": 170.0,
        "simulation.duration_s": 5.0,
    }
    run_scenario_file(S3.with_name("s1_pedestrian.toml"), tmp_path, junction, plots=False)
    replay = Replay(browser, tmp_path, "#step=45")
    drawn = replay.page.eval_on_selector_all("#layer-map path",
                                             "paths => paths.map(p => p.dataset.info)")
    assert [info.split("\n")[0] for info in drawn] == ["walkable area", "road", "crossings"]
    shown = replay.page.eval_on_selector_all("#layer-vehicles text",
                                             "labels => labels.map(t => t.textContent)")
    assert "bus" in shown and len(shown) > 1  # and the route file's vehicles
    assert replay.page.locator("circle.pedestrian").count() == 1
    assert replay.problems == []
