"""The jitter SUMO's walkers need, measured per network (sse_cosim/world/walker_jitter.py):
every passage of the paper road's walking areas walked alone at the speed bound in SUMO; the
measured jitter admits every one of those walks and is the least the worst one needs; it is
cached; a run takes it by default, keeps a larger one and refuses a smaller one."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import shapely
import sumolib
from world_helpers import REPO

from sse_cosim.cli.main import main
from sse_cosim.world import walker_jitter
from sse_cosim.world.assumptions import MotionBounds, admits, least_jitter
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.sumo import measure_walkers
from sse_cosim.world.walk_probe import Walker, walk_alone

pytestmark = pytest.mark.sumo
S1 = REPO / "scenarios" / "s1_pedestrian.toml"
SPEED, STEP, RADIUS = 2.5, 0.1, 0.3


@pytest.fixture
def paper(tmp_path, monkeypatch) -> tuple[Path, sumolib.net.Net]:
    """A copy of the paper road, its measurements cached in the test's own folder."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    net_path = tmp_path / "paper.net.xml"
    shutil.copyfile(build_network(REPO / "sumo_net"), net_path)
    return net_path, sumolib.net.readNet(str(net_path), withInternal=True,
                                         withPedestrianConnections=True)


def _measure(net_path: Path, speed: float) -> walker_jitter.NetworkJitter:
    """The walkers' measurement on the whole network at ``net_path``."""
    return measure_walkers(net_path, load_roadmap(net_path), None, speed, STEP, RADIUS)


def _areas(net: sumolib.net.Net) -> list:
    return [e for e in net.getEdges(withInternal=True) if e.getFunction() == "walkingarea"]


def test_every_passage_is_walked_but_a_turn_back(paper) -> None:
    _, net = paper
    walks = {edges for _, edges, _, _ in walker_jitter.passages(net, _areas(net))}
    # over the zebra both ways, from either sidewalk of each side, and along each side
    assert ("WC", ":C_w1", ":C_c0", ":C_w0", "CW") in walks
    assert ("EC", ":C_w0", ":C_c0", ":C_w1", "CE") in walks
    assert ("WC", ":C_w1", "CE") in walks and ("EC", ":C_w0", "CW") in walks
    # the dead ends' turns from one side of the road to the other are not walked
    assert not any(":E_w0" in edges or ":W_w0" in edges for edges in walks)
    assert len(walks) == 10


def test_the_measured_jitter_admits_every_walk_and_is_the_least_the_worst_needs(paper) -> None:
    net_path, net = paper
    measured = _measure(net_path, SPEED)
    assert measured.worst is not None and measured.worst.junction == "C"
    # the known jump: 0.80 m in a step on :C_w0_0 needs 0.334 m alone (docs/results.md)
    assert 0.334 <= measured.jitter_m <= 1.0
    walks = walker_jitter.passages(net, _areas(net))
    walkers = [Walker(f"w{i}", edges, depart, arrival, SPEED, depart_s=30.0 * i,
                      radius_m=RADIUS)
               for i, (_, edges, depart, arrival) in enumerate(walks)]
    traces = walk_alone(net_path, walkers, STEP, Path(net_path.parent / "probe"))
    at_measured = MotionBounds(SPEED, measured.jitter_m, STEP)
    assert all(admits(trace.xy, at_measured) for trace in traces.values())
    worst = next(traces[w.id] for w in walkers if w.edges == measured.worst.walk)
    # least_jitter is within 0.13 % + 2 mm of the least: 5 mm less does not admit the walk
    assert least_jitter(worst.xy, MotionBounds(SPEED, 0.0, STEP)) == measured.jitter_m
    assert not admits(worst.xy, MotionBounds(SPEED, measured.jitter_m - 0.005, STEP), 4096)
    # the walkable ground with the measured patches holds every position of every walk; the
    # plain ground does not (the curve over the zebra's walking areas leaves it by ~4 cm)
    roadmap = load_roadmap(net_path)
    walkable = roadmap.with_ground_patches(measured.ground_patches).walkable
    points = np.concatenate([trace.xy for trace in traces.values()])  # (k, 2)
    assert shapely.intersects_xy(walkable, points[:, 0], points[:, 1]).all()
    assert not shapely.intersects_xy(roadmap.ground, points[:, 0], points[:, 1]).all()
    assert set(measured.ground_patches) == {"C"}
    assert 0.0 < shapely.difference(measured.ground_patches["C"], roadmap.ground).area < 5.0


def test_a_measurement_is_cached_with_its_settings(paper, monkeypatch) -> None:
    net_path, _ = paper
    first = _measure(net_path, SPEED)

    def no_sumo(*args: object, **kwargs: object) -> None:
        raise AssertionError("measured again")

    monkeypatch.setattr(walker_jitter, "walk_alone_kept_on_error", no_sumo)
    assert _measure(net_path, SPEED) == first
    with pytest.raises(AssertionError, match="measured again"):  # another speed bound
        _measure(net_path, 2.0)


def test_runs_in_parallel_that_measure_different_junctions_lose_none(paper) -> None:
    """Two runs on one network open its cache before either has written, measure different
    junctions (their scopes differ) and write one after the other: the file keeps both."""
    net_path, _ = paper
    first, second = walker_jitter.JitterCache(net_path), walker_jitter.JitterCache(net_path)
    found = [walker_jitter.JunctionJitter(name, 0.5, ("WC",), ("WC_0", "WC_0"), 0.3,
                                          shapely.Point(0, 0)) for name in ("W", "E")]
    first.add("key", found[:1])
    second.add("key", found[1:])
    assert set(walker_jitter.JitterCache(net_path).junctions("key")) == {"W", "E"}
    assert set(second.junctions("key")) == {"W", "E"}


def test_a_cache_entry_without_its_walk_off_the_ground_is_measured_again(paper,
                                                                        monkeypatch) -> None:
    """Entries written before the walks' pieces off the ground were kept lack them (they kept
    the drawn patch instead): their junctions are walked again (the same jitter), and the
    pieces are kept from then on."""
    net_path, _ = paper
    first = _measure(net_path, SPEED)
    cache = walker_jitter.cache_path(net_path)
    entries = json.loads(cache.read_text("utf-8"))
    for junctions in entries.values():
        for entry in junctions.values():
            entry["ground_patch"] = entry.pop("off_ground")
    cache.write_text(json.dumps(entries), "utf-8")
    walked: list[int] = []
    real = walker_jitter.walk_alone_kept_on_error

    def counted(net: Path, walkers: list[Walker], *args: object, **kwargs: object) -> dict:
        walked.append(len(walkers))
        return real(net, walkers, *args, **kwargs)

    monkeypatch.setattr(walker_jitter, "walk_alone_kept_on_error", counted)
    assert _measure(net_path, SPEED) == first and len(walked) == 1
    assert all(entry["off_ground"] is not None
               for junctions in json.loads(cache.read_text("utf-8")).values()
               for entry in junctions.values())
    assert _measure(net_path, SPEED) == first and len(walked) == 1  # read from the cache


def test_the_patch_is_drawn_anew_from_the_cached_walk(paper, monkeypatch) -> None:
    """The cache keeps where SUMO's walkers left the ground, not the patch drawn around it: a
    wider band (or any change to the Region layer's dilation) gives the patch it draws
    without walking again, and holds the narrower one."""
    net_path, _ = paper
    narrow = _measure(net_path, SPEED).ground_patches["C"]

    def no_sumo(*args: object, **kwargs: object) -> None:
        raise AssertionError("measured again")

    monkeypatch.setattr(walker_jitter, "walk_alone_kept_on_error", no_sumo)
    monkeypatch.setattr(walker_jitter, "GROUND_BAND_M", 2.0 * walker_jitter.GROUND_BAND_M)
    wide = _measure(net_path, SPEED).ground_patches["C"]
    assert wide.covers(narrow) and wide.area > 1.5 * narrow.area


def _run(tmp_path: Path, *sets: str) -> dict:
    out = tmp_path / "out"
    main(["run", str(S1), "--out", str(out), "--set", "simulation.duration_s=2", *sets])
    return json.loads((out / "scenario.json").read_text())["estimator"]


def test_a_run_takes_the_measured_jitter_keeps_a_larger_one_and_refuses_a_smaller_one(
        tmp_path, capsys) -> None:
    measured = _measure(build_network(REPO / "sumo_net"), SPEED)
    assert _run(tmp_path)["position_jitter_m"] == measured.jitter_m
    assert _run(tmp_path, "--set", "estimator.position_jitter_m=1.5")["position_jitter_m"] == 1.5
    capsys.readouterr()  # the runs' progress (a measurement if the cache lacked one)
    with pytest.raises(SystemExit) as info:
        _run(tmp_path, "--set", "estimator.position_jitter_m=0.3")
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    for words in ("estimator.position_jitter_m", "0.3 m is below the "
                  f"{measured.jitter_m:.3f} m SUMO's lone walkers need", "junction 'C'",
                  "leave estimator.position_jitter_m out"):
        assert words in err, (words, err)


def test_a_network_converted_again_keeps_its_measurements(tmp_path: Path) -> None:
    """The cache of a network file outside a build is keyed by its bytes from the first element
    on: netconvert's header comment (the time of the conversion, its options) moves nothing;
    a change to the network itself does."""
    body = b'<net version="1.20">\n    <edge id="a"/>\n</net>\n'
    first, again, other = tmp_path / "first.net.xml", tmp_path / "again.net.xml", \
        tmp_path / "other.net.xml"
    first.write_bytes(b'<?xml version="1.0" encoding="UTF-8"?>\n\n<!-- generated on 2026-12-07T'
                      b'07:15:04 by Eclipse SUMO netconvert\n<netconvertConfiguration/>\n-->\n\n'
                      + body)
    again.write_bytes(b'<?xml version="1.0" encoding="UTF-8"?>\n<!-- generated on 2026-12-08T'
                      b'09:00:00 -->\n<!-- a second comment -->\n' + body)
    other.write_bytes(body.replace(b'"a"', b'"b"'))
    assert walker_jitter.cache_path(first) == walker_jitter.cache_path(again)
    assert walker_jitter.cache_path(first) != walker_jitter.cache_path(other)
    assert walker_jitter.net_digest(other) == hashlib.sha256(other.read_bytes()).hexdigest()
