"""V2X delivery and the polygon refinements (negative information)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
import shapely

from sse_cosim.estimation import occupancy
from sse_cosim.estimation.motion import MODELS, motion_model
from sse_cosim.estimation.occupancy import (
    COARSEN_M,
    GROUP_GAP_M,
    ClearRegion,
    EndedTrack,
    OccupancyTracker,
    TrackedWindow,
    UnobservedArea,
)
from sse_cosim.estimation.settings import EstimatorSettings, coast
from sse_cosim.estimation.v2x import Message, V2XLink
from sse_cosim.regions import PolygonRegion, kind, polygon
from sse_cosim.scenario.model import V2X, Estimator
from sse_cosim.sets import Strips, Zonotope

DT = 0.1
K = kind("polygon")


def R(shape: shapely.Geometry) -> PolygonRegion:
    return PolygonRegion(shape)


def dilate(shape: shapely.Geometry, distance: float) -> shapely.Geometry:
    return R(shape).dilate(distance).shape


def message(sender: str, step: int) -> Message:
    return Message(sender, step, {"ped": Zonotope(np.zeros(2), np.eye(2))},
                   R(shapely.box(0, 0, 1, 1)))


def test_latency_delays_delivery_and_newest_message_wins():
    link = V2XLink(V2X(latency_steps=2, drop_probability=0.0), np.random.default_rng(0))
    assert link.send(message("car", 0), distance_to_bus=10.0)
    assert link.deliver(1) == []
    assert [m.sent_step for m in link.deliver(2)] == [0]
    link.send(message("car", 3), 10.0)
    link.deliver(5)
    assert link.latest["car"].sent_step == 3


def test_out_of_range_and_dropped_messages_never_arrive():
    link = V2XLink(V2X(range_m=50.0, drop_probability=0.5), np.random.default_rng(1))
    assert not link.send(message("car", 0), distance_to_bus=60.0)
    sent = sum(link.send(message("car", k), 10.0) for k in range(400))
    assert 150 < sent < 250  # about half dropped, reproducibly for this seed


def test_stale_estimates_are_predicted_to_now():
    model = motion_model(Estimator(position_jitter_m=0.0), DT)
    link = V2XLink(V2X(latency_steps=3), np.random.default_rng(0))
    link.send(message("rsu1", 0), 5.0)
    link.deliver(3)
    aged = link.picture(3, model).estimates["ped"]["rsu1"]
    grown = 2.0 * (1.0 + 3 * model.max_speed * DT)
    assert abs(aged.volume() - grown**2) < 1e-9


@pytest.mark.parametrize("state_model", list(MODELS))
def test_a_silent_senders_estimates_coast_bounded_and_hold_the_exact_prediction(state_model):
    """Beyond the latency a received estimate is coasted (predicted, bounded, reduced): its
    generators stay at the budget however long the sender is silent, and (2-D, where the
    state bounds are none) it holds the exact prediction (support in every direction at least
    the exact one's); a picture asked again at an earlier step starts over from the
    message. (The 4-D model's coast is the unseen track's step, tested with the observer.)"""
    config = Estimator(state_model=state_model, position_jitter_m=0.0)
    model = motion_model(config, DT)
    settings = EstimatorSettings(config.gain_method, config.reduction_method,
                                 config.max_generators)
    link = V2XLink(V2X(latency_steps=1), np.random.default_rng(0),
                   partial(coast, model, settings))
    first = model.predict(Zonotope(np.zeros(2), np.eye(2))) if model.dim == 2 else \
        model.bound_state(model.initial_set(Strips(np.eye(2), np.zeros(2), np.ones(2)),
                                            config.gain_method))
    link.send(Message("car", 0, {"ped": first}, R(shapely.box(0, 0, 1, 1))), 5.0)
    link.deliver(1)
    angles = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    directions = np.zeros((24, model.dim))
    directions[:, 0], directions[:, 1] = np.cos(angles), np.sin(angles)
    for step in (1, 2, 30, 120):
        coasted = link.picture(step, model).estimates["ped"]["car"]
        exact = model.predict(first, step)
        assert coasted.n_generators <= max(settings.max_generators, first.n_generators
                                           + model.process_noise.n_generators)
        assert model.dim == 4 or np.all(coasted.support(directions)
                                        >= exact.support(directions) - 1e-9)
    again = link.picture(2, model).estimates["ped"]["car"]
    fresh = coast(model, settings, model.predict(first))
    np.testing.assert_array_equal(again.center, fresh.center)
    np.testing.assert_array_equal(again.generators, fresh.generators)


def test_the_picture_names_senders_whose_newest_message_reports_an_inconsistency():
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    link = V2XLink(V2X(latency_steps=0), np.random.default_rng(0))
    link.send(Message("car", 0, {}, K.empty(), inconsistent=True), 5.0)
    link.send(message("rsu1", 0), 5.0)
    link.deliver(0)
    assert link.picture(0, model).inconsistent == {"car"}
    link.send(message("car", 1), 5.0)  # the newer message counts
    link.deliver(1)
    assert not link.picture(1, model).inconsistent


def test_a_tracker_that_forgets_is_a_fresh_one():
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = R(shapely.box(-20, -20, 20, 20))
    used, fresh = OccupancyTracker(model, K, walkable), OccupancyTracker(model, K, walkable)
    small = {"ped": Zonotope(np.zeros(2), np.eye(2) * 0.5)}
    large = {"ped": Zonotope(np.zeros(2), np.eye(2) * 3.0)}
    used.update(0, small, {})
    assert used.update(1, large, {})["ped"].area < fresh.update(1, large, {})["ped"].area
    used.forget()
    assert used.update(2, large, {})["ped"].shape.equals(OccupancyTracker(model, K, walkable)
                                                         .update(2, large, {})["ped"].shape)


def test_dilate_circumscribes_the_disc():
    square = shapely.box(0, 0, 1, 1)
    grown = dilate(square, 1.0)
    for angle in np.linspace(0, 2 * np.pi, 73):
        corner_reach = shapely.Point(1 + np.cos(angle), 1 + np.sin(angle))
        assert grown.buffer(1e-9).covers(corner_reach)


def test_unobserved_area_is_cleared_by_views_and_grows_back_from_unseen_ground():
    model = motion_model(Estimator(position_jitter_m=0.0, max_pedestrian_speed_mps=1.0),
                         DT)
    walkable = R(shapely.box(0, 0, 20, 2))
    area = UnobservedArea(walkable, model, latency_steps=0, kind=K)
    seen = R(shapely.box(0, -1, 10, 3))
    first = area.update(0, seen, [])
    assert abs(first.area - 20.0) < 1e-6  # the half in view is clear
    regrown = area.update(1, K.empty(), [])
    # the cleared half regrows from the unseen half at 1 m/s: 0.1 m per step (+ polygon slack)
    assert 20.0 + 2 * 0.1 - 1e-6 <= regrown.area <= 2 * (10.0 + 0.1 * 1.1)


def test_shared_views_apply_at_the_step_they_were_taken():
    model = motion_model(Estimator(position_jitter_m=0.0, max_pedestrian_speed_mps=1.0),
                         DT)
    walkable = R(shapely.box(0, 0, 20, 2))
    area = UnobservedArea(walkable, model, latency_steps=2, kind=K)
    for step in range(2):
        area.update(step, K.empty(), [])
    # the view taken at step 0 arrives at step 2: carried two steps forward, not eroded
    now = area.update(2, K.empty(), [R(shapely.box(-1, -1, 21, 3))])
    assert now.is_empty


def test_known_pedestrian_region_excludes_clear_regions_and_keeps_the_truth():
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    tracker = OccupancyTracker(model, K)
    fused = {"ped": Zonotope(np.array([5.0, 0.0]), np.eye(2) * 3.0)}
    view = R(shapely.box(0, -5, 4, 5))  # saw x < 4 without the pedestrian
    region = tracker.update(0, fused, {"ped": [ClearRegion(view, 0)]})["ped"].shape
    assert not region.intersects(shapely.box(0, -2, 3.5, 2))
    assert region.covers(shapely.Point(6.0, 1.0))


def test_windowed_unobserved_area_keeps_everything_the_full_tracker_has_inside_the_window():
    """Tracking only around the window (ground outside counts as unseen) loses nothing inside
    it: checked against the whole-walkable tracker on random views, with latency."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = shapely.union(shapely.box(0, 0, 60, 2), shapely.box(28, -8, 32, 10))
    window = shapely.box(24, -6, 36, 8)
    rng = np.random.default_rng(7)
    for latency in (0, 2):
        full = UnobservedArea(R(walkable), model, latency, K)
        windowed = UnobservedArea(R(walkable), model, latency, K, window=R(window))
        for step in range(40):
            x, y = rng.uniform(0, 60), rng.uniform(-8, 10)
            own = R(shapely.box(x, y, x + rng.uniform(2, 30), y + rng.uniform(2, 15)))
            shared = [R(shapely.box(20, -10, 40, 12))] if rng.random() < 0.5 else []
            expected = full.update(step, own, shared).shape.intersection(window)
            got = windowed.update(step, own, shared).shape
            assert expected.difference(got.buffer(1e-7)).area < 1e-9, (latency, step)
        everything = R(shapely.box(-10, -20, 70, 20))
        cleared = windowed.update(40 + latency, everything, [everything]).shape
        # seen everywhere now (latency 0): only paths just entering across the rim remain
        assert latency or cleared.intersection(window.buffer(-1.5)).is_empty


def test_the_kept_move_of_the_base_is_the_move_computed_afresh():
    """The unobserved area keeps the base's moved region for the next step: with latency 1
    and 2 and random views, every step equals that of an area made to forget it."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = shapely.union(shapely.box(0, 0, 60, 2), shapely.box(28, -8, 32, 10))
    window = shapely.box(24, -6, 36, 8)
    rng = np.random.default_rng(11)
    for latency in (1, 2):
        kept = UnobservedArea(R(walkable), model, latency, K, window=R(window))
        afresh = UnobservedArea(R(walkable), model, latency, K, window=R(window))
        for step in range(30):
            x, y = rng.uniform(0, 60), rng.uniform(-8, 10)
            own = R(shapely.box(x, y, x + rng.uniform(2, 30), y + rng.uniform(2, 15)))
            shared = [R(shapely.box(20, -10, 40, 12))] if rng.random() < 0.5 else []
            afresh._base_moved = {}
            assert kept.update(step, own, shared).shape.equals_exact(
                afresh.update(step, own, shared).shape, 0.0), (latency, step)
        assert kept._base_moved


def test_a_window_in_pieces_far_apart_is_tracked_in_groups_as_it_is_whole(monkeypatch):
    """A long route's window: three crossings along 400 m of sidewalk, far apart. Tracked in
    groups, with steps at rest looked up, the unobserved area and its path region are, at
    every step, the sets tracked for the whole window at once, under random
    views near one crossing or another, shared views with latency and a track handed over;
    and the crossing no view comes near keeps its whole ground as it is, not computed.
    (Without coarsening: a region
    of more vertices, as the whole window's is, is coarsened where a group's alone is not, and
    each grows from there.)"""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    crossings = [shapely.box(x - 2, -8, x + 2, 10) for x in (50.0, 200.0, 350.0)]
    walkable = shapely.union_all([shapely.box(0, 0, 400, 2), *crossings])
    window = shapely.union_all([c.buffer(6.0) for c in crossings])
    track = EndedTrack(12, Zonotope(np.array([200.0, 1.0]), np.eye(2) * 0.5))
    monkeypatch.setattr(polygon, "COARSEN_ABOVE", 10**9)
    for latency in (1, 2):
        rng = np.random.default_rng(3 + latency)
        grouped = UnobservedArea(R(walkable), model, latency, K, window=R(window))
        monkeypatch.setattr(occupancy, "GROUP_GAP_M", 1e9)
        whole = UnobservedArea(R(walkable), model, latency, K, window=R(window))
        monkeypatch.setattr(occupancy, "GROUP_GAP_M", GROUP_GAP_M)
        assert (len(grouped._groups), len(whole._groups)) == (3, 1)
        for step in range(40):
            x = rng.choice([50.0, 200.0]) + rng.uniform(-10, 10)
            own = R(shapely.box(x, -6, x + rng.uniform(2, 12), rng.uniform(0, 9)))
            shared = [R(shapely.box(195, -10, 205, 12))] if rng.random() < 0.3 else []
            ended = [track] if step == 12 + latency else []
            got = grouped.update(step, own, shared, ended).shape
            expected = whole.update(step, own, shared, ended).shape
            assert got.symmetric_difference(expected).area < 1e-7, (latency, step)
            assert grouped.path.shape.symmetric_difference(whole.path.shape).area < 1e-7
        far = next(k for k, g in enumerate(grouped._groups) if g.tracked.bounds[0] > 300.0)
        assert grouped._paths[far] is grouped._whole[far]  # whole, as it was made


def test_a_crossing_seen_and_left_alone_fills_again_and_its_steps_at_rest_are_looked_up():
    """A group cleared by a view and then left alone (no view, no hand-over) grows back over
    its ground, step by step, and once GEOS's overlays repeat a region its steps are looked
    up (the group's rest), the region staying the ground it grew back to."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    crossings = [shapely.box(x - 2, -8, x + 2, 10) for x in (50.0, 200.0, 350.0)]
    walkable = shapely.union_all([shapely.box(0, 0, 400, 2), *crossings])
    window = shapely.union_all([c.buffer(6.0) for c in crossings])
    area = UnobservedArea(R(walkable), model, 1, K, window=R(window))
    view = R(shapely.box(190, -10, 210, 12))
    middle = next(k for k, g in enumerate(area._groups) if 150.0 < g.tracked.bounds[0] < 250.0)
    areas = [area.update(step, view, []).area for step in range(2)]
    step = 2
    while area._groups[middle].rest.get(area._paths[middle]) is None:
        areas.append(area.update(step, K.empty(), []).area)
        step += 1
        assert step < 200
    assert np.all(np.diff(areas[1:]) > -1e-9) and areas[-1] > areas[1] + 50.0
    assert area._paths[middle].area == pytest.approx(area._whole[middle].area, rel=1e-6)


def test_a_known_region_kept_in_the_window_holds_the_pedestrian_who_leaves_and_comes_back():
    """A pedestrian walks out of the window along a sidewalk, hidden, and back in while views
    clear the sidewalk where it is not: at every step it is in its region or outside the
    window (also across a step without an update); the region stays within the window's
    bounds; once it is seen back inside, it is no longer counted as possibly beyond. The
    region without the window grows far larger."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = shapely.box(0, 0, 120, 3)
    window = shapely.box(20, -5, 40, 8)
    bounds = dilate(window, model.jitter).buffer(1e-9)
    step_length = model.max_speed * DT
    for seed in range(4):
        rng = np.random.default_rng(seed)
        windowed = OccupancyTracker(model, K, R(walkable), R(window))
        whole = OccupancyTracker(model, K, R(walkable))
        truth, estimate, heading, largest = np.array([30.0, 1.5]), None, 1.0, 0.0
        for step in range(700):
            if truth[0] > 75.0:
                heading = -1.0  # and back
            elif heading < 0 and truth[0] < 26.0:
                heading = 0.0  # and stays
            truth = truth + np.array([heading * rng.uniform(0.6, 1.0) * step_length, 0.0])
            truth[1] = np.clip(truth[1] + rng.uniform(-0.1, 0.1), 0.2, 2.8)
            seen = truth[0] < 36.0 or (heading < 0 and truth[0] < 30.0)
            if seen or estimate is None:
                estimate = Zonotope(truth.copy(), np.eye(2) * 0.4)
            else:
                estimate = model.predict(estimate)
            if step % 9 == 4:
                continue  # a step without an update: the next one moves two steps
            x0 = rng.uniform(0, 110)
            views = [shapely.box(x0, -1, x0 + rng.uniform(2, 12), 4)]
            clear = [ClearRegion(R(v), 0) for v in views
                     if v.distance(shapely.Point(truth)) > 1e-3]
            region = windowed.update(step, {"p": estimate}, {"p": clear})["p"].shape
            largest = max(largest, whole.update(step, {"p": estimate}, {"p": clear})["p"].area)
            point = shapely.Point(truth)
            assert region.buffer(1e-7).covers(point) or not window.contains(point), (seed, step)
            # in B, grown by the jitter and by coarsening's cover
            assert region.difference(dilate(bounds, model.jitter + 2 * COARSEN_M)).is_empty
            if seen and truth[0] < 34.0:
                assert "p" not in windowed.beyond, (seed, step)
        assert truth[0] < 30.0  # it came back
        kept = shapely.intersection(dilate(walkable, 2 * model.jitter), dilate(bounds, 0.3))
        assert largest > 2 * kept.area  # the region not kept in the window outgrows it


def test_the_inflow_holds_every_path_that_enters_the_bounds_from_outside():
    """A path s outside B (on walkable (+) disc(eps)) that moves at most ``steps`` times the
    reach of a step ends, if inside B, inside the inflow of that many steps."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = shapely.union(shapely.box(0, 0, 60, 2), shapely.box(28, -8, 32, 10))
    window = shapely.box(24, -6, 36, 8)
    tracked = TrackedWindow(R(window), R(walkable), model, K)
    ground = dilate(walkable, model.jitter)
    bounds = tracked.tracked.shape
    rng = np.random.default_rng(5)
    for steps in (1, 2, 5):
        inflow = tracked.inflow(steps).shape.buffer(1e-7)
        entered = 0
        x0, y0, x1, y1 = bounds.buffer(model.reach_m(steps)).bounds
        for _ in range(20000):
            start = shapely.Point(rng.uniform(x0, x1), rng.uniform(y0, y1))
            if not ground.contains(start) or bounds.contains(start):
                continue
            angle, length = rng.uniform(0, 2 * np.pi), rng.uniform(0, model.reach_m(steps))
            end = shapely.Point(start.x + length * np.cos(angle), start.y + length * np.sin(angle))
            if bounds.contains(end):
                entered += 1
                assert inflow.covers(end), (steps, start, end)
        assert entered > 50


def test_ground_nobody_saw_off_the_walkable_keeps_no_path_alive():
    """The sidewalk was seen clear, the road beside it (a vehicle's shadow) was not: a
    pedestrian, who stays on walkable ground, cannot have been on the road, so its region
    keeps nothing of the sidewalk's middle. Without walkable ground the shadow within the
    jitter keeps the strip next to it."""
    model = motion_model(Estimator(position_jitter_m=1.0), DT)
    sidewalk, road = shapely.box(-10, -3, 10, 0), shapely.box(-10, 0, 10, 7)
    fused = {"ped": Zonotope(np.array([0.0, -1.5]), np.diag([8.0, 1.5]))}
    seen = [ClearRegion(R(shapely.box(-20, -20, 20, 0)), 0)]  # the sidewalk side, not the road
    kept = OccupancyTracker(model, K, R(sidewalk)).update(0, fused, {"ped": seen})["ped"].shape
    assert kept.intersection(shapely.box(-5, -3, 5, 0)).is_empty
    plain = OccupancyTracker(model, K).update(0, fused, {"ped": seen})["ped"].shape
    assert not plain.intersection(shapely.box(-5, -1, 5, 0)).is_empty
    assert not road.is_empty
