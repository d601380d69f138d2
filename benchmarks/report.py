"""``benchmarks.md`` from the results dictionary of :func:`benchmarks.run.run_all`."""

from __future__ import annotations

from benchmarks.loop_cost import ANONYMOUS, DEFAULT
from sse_cosim.scenario.model import Estimator


def _f(value, digits: int = 1) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:,.{digits}f}"
    return str(value)


def _load(values) -> str:
    return "–" if not values else ", ".join(f"{v:.1f}" for v in values)


def _verdict(ok: bool) -> str:
    return "**met**" if ok else "**not met**"


def markdown(r: dict) -> str:
    m = r["machine"]
    t = r["targets"]
    lines = [
        "# Benchmarks",
        "",
        f"Produced by `{r['command']}` in {r['total_seconds']:.0f} s.",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, SUMO {m['sumo']}, "
        f"numpy {m['numpy']}, scipy {m['scipy']}, shapely {m['shapely']}, cvxpy {m['cvxpy']} "
        f"({m['platform']}). Load average when it started (1, 5, 15 min): "
        f"{_load(m.get('load_average_at_start'))} — other jobs on the machine slow every "
        "figure alike; the ratios are what to compare.",
        "",
        "Timings are medians over repeated runs; every ratio compares figures measured side by "
        "side in the same process. `results/benchmarks.json` holds every figure.",
        "",
    ]
    if r.get("quick"):
        lines += ["**Quick (smoke) run: tiny sizes, figures not meaningful.**", ""]
    lines += _summary(r, t)
    if "loop_cost" in r:
        lines += _loop(r["loop_cost"], t)
    if "gain_methods" in r:
        lines += _gains(r["gain_methods"])
    if "kernels" in r:
        lines += _kernels(r["kernels"])
    if "scaling" in r:
        lines += _scaling(r["scaling"], t)
    if "crowd" in r:
        lines += _crowd(r["crowd"])
    if "throughput" in r:
        lines += _throughput(r["throughput"], t)
    if "cluster" in r:
        lines += _cluster(r["cluster"])
    if "tightness" in r:
        lines += _tightness(r["tightness"], t)
    if "arrivals" in r:
        lines += _arrivals(r["arrivals"])
    if "soundness" in r:
        lines += _soundness(r["soundness"])
    if "baseline" in r:
        lines += _baseline(r["baseline"])
    if "campaign" in r:
        lines += _campaign(r)
    for key, detections in (("profile_default_gain", "default methods"),
                            ("profile_anonymous", "default methods, anonymous detections")):
        if r.get("loop_cost", {}).get(key):
            lines += [f"## Profile of one run (S3 with the pedestrian, {detections})", "",
                      "cProfile, cumulative time; the stage table above attributes the same "
                      "time to the loop's stages.", "", "```", r["loop_cost"][key], "```", ""]
    return "\n".join(lines) + "\n"


def _summary(r: dict, t: dict) -> list[str]:
    rows = []
    budgets: dict[str, str] = {}  # a cost-per-step row's name -> what must go to meet it
    loop = r.get("loop_cost", {}).get("configs", {})
    if DEFAULT in loop:
        rows += _loop_rows(r["loop_cost"], t, budgets)
    for name, c in loop.items():
        if name.startswith("b_") and "ratio_to_a" in c:
            rows.append((f"1b co-sim ({c['gain_method']}) / (a)", f"{c['ratio_to_a']:.1f}×",
                         f"≤ {t['loop_b_ratio_to_a']:.0f}×",
                         c["ratio_to_a"] <= t["loop_b_ratio_to_a"]))
    if ANONYMOUS in loop:
        rows.append(_anonymous_row("1c anonymous / labelled detections, S3", loop[ANONYMOUS],
                                   loop[DEFAULT], t, budgets))
    for op, ratio in r.get("kernels", {}).get("ratios", {}).items():
        value = ratio["compiled / peer"]
        if value is not None and f"kernels_ratio_to_{ratio['peer']}" in t \
                and op in t["kernel_targets"]:
            peer = {"zonoopt": "ZonoOpt", "shapely": "shapely"}[ratio["peer"]]
            limit = t[f"kernels_ratio_to_{ratio['peer']}"]
            rows.append((f"kernel {op}: compiled / {peer}", f"{value:.2f}×", f"≤ {limit:g}×",
                         value <= limit))
    if "scaling" in r:
        k = r["scaling"]["exponent_in_pedestrians_x_sensors"]
        rows.append(("3 cost exponent in pedestrians × sensors", f"{k:.2f}", "≤ 1", k <= 1.0))
        largest = r["scaling"].get("largest")
        if largest is not None and "scaling_largest_ms" in t:
            ms, limit = largest["us_per_step"] / 1000, t["scaling_largest_ms"]
            rows.append((f"3 {largest['pedestrians']} pedestrians × {largest['sensors']} "
                         "sensors, ms per step", f"{ms:.1f}", f"≤ {limit:g}", ms <= limit))
    if "crowd" in r:
        c = r["crowd"]
        ms, limit = c["us_per_step"] / 1000, t["crowd_ms"]
        name = f"3b crowd ({c['pedestrians']} pedestrians, real SUMO), ms per step"
        rows.append((name, f"{ms:.1f} ({c['ratio_to_bare']:.0f}× bare SUMO)", f"≤ {limit:g}",
                     ms <= limit))
        budgets[name] = _budget(c, 1000 * limit, f"≤ {limit:g} ms")
        rows.append(_anonymous_row("3b anonymous / labelled detections, crowd", c["anonymous"],
                                   c, t, budgets))
    if "throughput" in r:
        s = r["throughput"]["configs"]["local_2"]["speedup_vs_1_worker"]
        rows.append(("4 sweep speed-up, 2 local workers", f"{s:.2f}×", "≥ 1.8×", s >= 1.8))
        if "dask_2" in r["throughput"]["configs"]:
            d = r["throughput"]["configs"]["dask_2"]["speedup_vs_1_worker"]
            rows.append(("4 sweep speed-up, Dask 2 workers", f"{d:.2f}×", "≥ 1.8×", d >= 1.8))
    if "cluster" in r:
        c = r["cluster"]
        rows.append((f"4 Dask cluster / local pool, runs per minute ({c['runs']} runs)",
                     f"{c['dask_over_local']:.2f}", "≥ 0.9, rows identical",
                     c["dask_over_local"] >= t["cluster_ratio_to_local"] and c["rows_identical"]))
    if "tightness" in r:
        tt = r["tightness"]
        for kind in ("fused", "local"):
            best = tt[f"best_{kind}"]
            mean = tt[kind][best].get("mean")
            if mean is not None:
                rows.append((f"5 {kind} area / exact, best (`{_cell(best)}`)", f"{mean:.2f}",
                             "mean ≤ 1.3", mean <= t["tightness_best_mean"]))
        defaults = Estimator()
        name = f"{defaults.gain_method}|{defaults.fusion_method}"
        default = tt["fused"].get(name, {}).get("mean")
        if default is not None:
            rows.append((f"5 fused area / exact, default (`{_cell(name)}`)", f"{default:.2f}",
                         "mean ≤ 1.3", default <= t["tightness_best_mean"]))
    if "arrivals" in r:
        a, limit = r["arrivals"]["all"], t["arrivals_ratio_of_means"]
        ratio = a["ratio_of_means"]
        rows.append(("5b earliest arrival, controller / exact reference, mean",
                     "–" if ratio is None else f"{ratio:.4f} ({a['later_than_reference']} "
                     f"of {a['zone_steps']:,} zone-steps later)", f"≥ {limit:g}, 0 later",
                     ratio is not None and ratio >= limit and a["later_than_reference"] == 0))
    if "soundness" in r:
        s = r["soundness"]
        rows.append(("6 soundness: violations / node-steps",
                     f"{s['violations']} / {s['node_steps']:,}", "0 / ≥ 100,000",
                     s["violations"] == 0 and s["node_steps"] >= t["soundness_node_steps"]))
    if "baseline" in r:
        b = r["baseline"]["open_loop_total"]
        share = 100 * (b["kf_miss_share"] or 0)
        rows.append(("7 KF 3-sigma ellipse misses the truth",
                     f"{share:.1f} % of {b['steps']} steps",
                     f"(zonotopes: {b['zonotope_misses']})", None))
    if "campaign" in r:
        name = SAFETY_ROW
        minutes, limit = _projected(r), t["safety_minutes_2_cores"]
        rows.append((name, f"{minutes:.0f}", f"≤ {limit:g}", minutes <= limit))
        budgets[name] = _campaign_budget(r, limit)
    else:
        rows.append((SAFETY_ROW, "not measured", f"≤ {t['safety_minutes_2_cores']:g}", None))
    lines = ["## Targets", "", "| figure | measured | target | |", "|---|---|---|---|"]
    for name, value, target, ok in rows:
        lines.append(f"| {name} | {value} | {target} | "
                     f"{'' if ok is None else _verdict(ok)} |")
    missed = [(name, step + budgets.get(name, "")) for name, _, _, ok in rows
              if ok is False for prefix, step in NEXT_STEPS.items() if name.startswith(prefix)]
    if missed:
        lines += ["", "Each target not met, where its time goes and the next step:", ""]
        lines += [f"- **{name}**: {step}" for name, step in missed]
    return [*lines, ""]


def _loop_rows(loop: dict, t: dict, budgets: dict[str, str]) -> list[tuple]:
    """Item 1's rows: the default methods against libsumo alone (the target), and bare SUMO
    through the project's world against libsumo alone (information)."""
    config, limit = loop["configs"][DEFAULT], t["loop_default_ratio_to_libsumo"]
    name = "1 co-sim (default methods) / libsumo alone"
    budgets[name] = _budget(config, limit * loop["libsumo_us_per_step"],
                            f"≤ {limit:g}× libsumo alone")
    return [(name, f"{config['ratio_to_libsumo']:.0f}×", f"≤ {limit:g}×",
             config["ratio_to_libsumo"] <= limit),
            ("1 bare SUMO through `SumoWorld` (the project's snapshot) / libsumo alone",
             f"{loop['bare_ratio_to_libsumo']:.1f}×", "(information)", None)]


def _anonymous_row(name: str, anonymous: dict, labelled: dict, t: dict,
                   budgets: dict[str, str]) -> tuple:
    """A row of anonymous detections' cost per step against labelled ones, measured side by
    side; its budget and the stages that grew the most."""
    ratio, limit = anonymous["ratio_to_labelled"], t["anonymous_ratio_to_labelled"]
    budgets[name] = (_budget(anonymous, limit * labelled["us_per_step"],
                             f"≤ {limit:g}× labelled")
                     + _growth(anonymous["stages_us"], labelled["stages_us"]))
    return (name, f"{ratio:.2f}×", f"≤ {limit:g}×", ratio <= limit)


def _budget(config: dict, allowed_us: float, limit: str) -> str:
    """For a cost-per-step target (``limit``, at most ``allowed_us`` per step): how much of
    ``config``'s step must go to meet it, against its largest stage."""
    excess = config["us_per_step"] - allowed_us
    stage, largest = max(config["stages_us"].items(), key=lambda item: item[1])
    return (f" At {limit} a step may take {allowed_us:,.0f} µs; it takes "
            f"{config['us_per_step']:,.0f}, so {excess:,.0f} µs must go "
            f"({'more' if excess > largest else 'less'} than its largest stage, `{stage}`, "
            f"at {largest:,.0f} µs).")


def _growth(stages: dict[str, float], reference: dict[str, float], top: int = 2) -> str:
    """The ``top`` stages that grew the most from ``reference`` to ``stages`` (µs per step)."""
    grown = sorted(((stages[s] - reference.get(s, 0.0), s) for s in stages), reverse=True)
    parts = [f"`{s}` +{delta:,.0f} µs" for delta, s in grown[:top] if delta > 0]
    return f" Against labelled detections: {', '.join(parts)} per step." if parts else ""


LOOP_STEP = ("the stage table (item 1) and the profile at the end of this file: most of a step "
             "is shapely's overlay calls (buffer, intersection, difference, union) behind the "
             "Region layer, on small polygons one pedestrian and one view at a time, in the "
             "occupancy and screening stages, and the Python around each call. The raster "
             "representation (`estimator.regions = \"raster\"`) is sound but no faster one "
             "operation at a time (docs/method.md, \"Regions\"). Next: one compiled call per "
             "step for every pedestrian's region on a shared grid (the path regions' "
             "recurrence and the negative information's cuts as mask operations), so that the "
             "per-call cost is paid once a step, not once a pedestrian and view.")
ANONYMOUS_STEP = ("the stage tables (item 1: `anonymous` against `default_enclose`; item 3b) "
                  "and the profile of the anonymous run at the end of this file: the extra "
                  "time is the nodes' set-membership association "
                  "(`estimation.association.associate`, in `local_fusion`), whose possibilities "
                  "and candidates are Region overlays (buffer, intersection, difference), one "
                  "track and one sensor's view at a time. Next: every track of a node at once, "
                  "in the batched region step of item 1's next step.")
NEXT_STEPS = {
    "1 co-sim": LOOP_STEP,
    "1b": LOOP_STEP,
    "1c anonymous": ANONYMOUS_STEP,
    "3b anonymous": ANONYMOUS_STEP,
    "3b crowd": "the stage line of item 3b: the negative information (`occupancy`: every "
                "known pedestrian's region and the unobserved area), the bus's screening and "
                "fusion (`sharing_fusion`) and the recorder's checks (`output`) each work one "
                "pedestrian at a time. Next: one compiled region step for every pedestrian at "
                "once (item 1's next step), and the bus's screening (a set against the views "
                "it may lie in) and fusion batched over the pedestrians.",
    "kernel enclose": "the table of item 2: *kernel alone* is the one compiled call "
                      "(strips normalized, clipped, enclosed, the volume gain as its "
                      "fallback); *compiled* adds the public function's Python (checks, "
                      "wrapping the result), and shapely's own time moves a great deal from "
                      "run to run on this machine. Next: the checks and the wrapping folded "
                      "into the call, so the public function is the kernel.",
    "3 ": "the profile of the largest configuration (item 3): a node's plain track updates "
          "are one compiled call per node and step; what is left is the bus's refined region "
          "of every known pedestrian (shapely's buffer and overlay calls, one pedestrian at a "
          "time, against every node's view), the fusion of each pedestrian's sets and the "
          "sensors' strips. Next: item 1's next step, one compiled region step for every "
          "pedestrian at once.",
    "4 Dask cluster": "item 4b, its CPU table: the cluster's own processes (scheduler, "
                      "nannies, Dask workers) take CPU time beside the runs on the same 2 "
                      "cores, while the local pool pays its workers' start-up in each half. "
                      "Next: run the cluster's scheduler off the workers' cores, as on a real "
                      "cluster, or quiet its per-worker bookkeeping (heartbeats, memory "
                      "monitor).",
    "8 ": "item 8, its table: the crowd's and the junction's runs are most of the campaign "
          "(long scenes, many pedestrians or two buses, every step's occupancy and screening "
          "one pedestrian at a time, items 1 and 3b). Next: item 1's next step (one compiled "
          "region step for every pedestrian) shortens every run, the crowd's the most.",
    "4 sweep": "item 4: the speed-up of the whole batch, each worker's start-up inside it "
               "(measured alone under the table: imports, then numba loading its cached "
               "kernels and SUMO's first start in the first run); on 2 cores the main "
               "process, and any other job on the machine, also take their share beside two "
               "workers. Next: a shorter start-up (fewer kernels for numba to load, fewer "
               "imports in the worker), or workers that stay up from one batch to the next.",
}
"""By the start of a target's name in the summary: where its profile is and the next step."""

SAFETY_ROW = "8 `make safety` (the whole campaign), minutes on 2 cores, projected"


ASSUMED_SPEEDUP = 2.0  # two workers counted as twice one, without item 4


def _speedup(r: dict) -> float | None:
    """Item 4's speed-up of two local workers over one (None without item 4)."""
    if "throughput" not in r:
        return None
    return r["throughput"]["configs"]["local_2"]["speedup_vs_1_worker"]


def _projection_speedup(r: dict) -> float:
    """The speed-up item 8's projection divides by: item 4's, or :data:`ASSUMED_SPEEDUP`."""
    return _speedup(r) or ASSUMED_SPEEDUP


def _projected(r: dict) -> float:
    """Item 8's projection (minutes)."""
    from benchmarks.campaign import projected_minutes

    return projected_minutes(r["campaign"], _projection_speedup(r))


def _campaign_budget(r: dict, limit: float) -> str:
    """For the campaign's target: how many minutes must go, against its largest scenario."""
    minutes, speedup = _projected(r), _projection_speedup(r)
    stem, largest = max(((s, c["serial_minutes"] / speedup)
                         for s, c in r["campaign"]["scenarios"].items()), key=lambda x: x[1])
    return (f" At ≤ {limit:g} minutes; it takes {minutes:.0f}, so {minutes - limit:.0f} "
            f"minutes must go (its largest part, `{stem}`'s runs, takes {largest:.0f}).")


def _loop(loop: dict, t: dict) -> list[str]:
    stages = list(next(iter(loop["configs"].values()))["stages_us"])
    read = loop["libsumo_actors_read"]
    lines = [
        "## 1. Cost per step against libsumo alone and bare SUMO",
        "",
        f"`{loop['scenario']}`, {loop['steps']} steps of 0.1 s with the default methods, "
        f"{loop['repeats']} repeats (median). Fusion method `{loop['fusion_method']}` (the "
        "default) in every configuration, whatever the nodes' correction. The co-simulation "
        "includes the recorder (trace rows, containment checks), not the file writing at the "
        "end of a run.",
        "",
        f"*libsumo alone*: libsumo loads the SUMO configuration the co-simulation wrote for "
        f"its run (`sumo.sumocfg`: same network, routes and seed), steps it as many steps and "
        f"reads every actor's position, angle and speed each step (each vehicle and person "
        f"subscribed at its departure, every domain's results in one call; "
        f"{read['vehicles']} vehicle(s) and {read['persons']} person(s) read), nothing commanded: "
        f"**{loop['libsumo_us_per_step']:,.1f} µs/step**. *Bare SUMO*: the same network, "
        "routes and steps through the project's world (`SumoWorld.step`: the snapshot and "
        "the world's per-step checks), the bus commanded to its nominal speed, no sensor "
        f"layer: **{loop['bare_us_per_step']:,.0f} µs/step** "
        f"({loop['bare_ratio_to_libsumo']:.1f}× libsumo alone; real-time factor "
        f"{loop['bare_real_time_factor']:,.0f}).",
        "",
        "| configuration | gain | detections | steps | µs/step | / libsumo alone | / bare "
        "| / (a) | / labelled | real-time factor |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, c in loop["configs"].items():
        lines.append(f"| {name} | `{c['gain_method']}` | {c['association']} | {c['steps']} | "
                     f"{c['us_per_step']:,.0f} | {c['ratio_to_libsumo']:,.0f}× | "
                     f"{c['ratio_to_bare']:.1f}× | {_f(c.get('ratio_to_a'), 1)} | "
                     f"{_f(c.get('ratio_to_labelled'), 2)} | {c['real_time_factor']:.1f} |")
    lines += ["", "µs per step of each stage (`sse_cosim.runner.timing.StageTimer`):", "",
              "| configuration | " + " | ".join(stages) + " |",
              "|---|" + "---|" * len(stages)]
    for name, c in loop["configs"].items():
        lines.append(f"| {name} | " + " | ".join(f"{c['stages_us'][s]:,.0f}" for s in stages)
                     + " |")
    lines += ["", "Stages: `sumo` SUMO step and snapshot; `geometry` sensors (line of sight, "
              "visible/occluded regions, strips); `local_fusion` every node's observer (with "
              "anonymous detections, its association too); `sharing_fusion` V2X, consistency "
              "screen and fusion at the bus; `occupancy` "
              "negative information (known pedestrians' regions, unobserved area); `control` "
              "picture, level, command; `output` the recorder.", ""]
    return lines


def _gains(g: dict) -> list[str]:
    lines = ["## 2. Gain methods", "", f"Problem: {g['problem']}.", "",
             "| method | µs per call |", "|---|---|"]
    lines += [f"| {k} | {v:,.0f} |" for k, v in g["us_per_call"].items()]
    lines += ["", "| ratio | |", "|---|---|"]
    lines += [f"| {k} | {v:.1f}× |" for k, v in g["ratios"].items()]
    lines += ["", "Result areas (m²): " + ", ".join(f"{k} {v:.3f}"
                                                     for k, v in g["result_area_m2"].items()),
              ""]
    return lines


def _kernels(k: dict) -> list[str]:
    lines = ["## Compiled kernels", "",
             "µs per call, same process: the compiled kernel (numba) through the public "
             "function, its NumPy reference, and a peer: ZonoOpt"
             + ("" if k["zonoopt"] else " (not installed: `pip install -e \".[bench]\"`)")
             + " for the first three, shapely clipping the same polygons for the `enclose` "
             "ones. Problems: " + "; ".join(f"{op} {p}" for op, p in k["problems"].items())
             + ". *Kernel alone*: the compiled kernel called on the arrays, without the public "
             "function's Python (checks, strip normalization, wrapping the result).", "",
             "| operation | compiled | kernel alone | reference | peer | compiled / peer "
             "| reference / compiled |", "|---|---|---|---|---|---|---|"]
    for op, us in k["us_per_call"].items():
        ratio = k["ratios"][op]
        peer = ratio["peer"]
        lines.append(f"| {op} | {us['compiled']:,.1f} | {_f(us.get('kernel alone'))} | "
                     f"{us['reference']:,.1f} | "
                     f"{_f(us.get(peer))}{f' ({peer})' if peer else ''} | "
                     f"{_f(ratio['compiled / peer'], 2)} | "
                     f"{ratio['reference / compiled']:.1f}× |")
    return [*lines, ""]


def _scaling(s: dict, t: dict) -> list[str]:
    grid = s["grid"]
    peds = sorted({g["pedestrians"] for g in grid})
    sens = sorted({g["sensors"] for g in grid})
    cell = {(g["pedestrians"], g["sensors"]): g["us_per_step"] for g in grid}
    lines = ["## 3. Scaling (synthetic scene, no SUMO)", "",
             f"ms per step (median of {s['steps']} steps after {s['warmup']} warm-up steps); "
             "rows: pedestrians, columns: sensors.", "",
             "| pedestrians \\ sensors | " + " | ".join(str(x) for x in sens) + " |",
             "|---|" + "---|" * len(sens)]
    for p in peds:
        lines.append(f"| {p} | " + " | ".join(_f(cell.get((p, x), 0) / 1000, 1) for x in sens)
                     + " |")
    lines += ["", f"Fit log(cost) = a + k log(pedestrians × sensors): **k = "
              f"{s['exponent_in_pedestrians_x_sensors']:.2f}** (target ≤ 1). Separately: "
              f"pedestrians {s['exponent_pedestrians']:.2f}, sensors {s['exponent_sensors']:.2f}; "
              f"the cost above the 1 × 1 step grows with exponent "
              f"{_f(s['marginal_exponent'], 2)}.", ""]
    if s.get("profile_largest"):
        largest = s["largest"]
        lines += [f"Profile of the largest configuration ({largest['pedestrians']} pedestrians "
                  f"× {largest['sensors']} sensors, its warm-up and timed steps; cProfile, "
                  "internal time):", "", "```", s["profile_largest"], "```", ""]
    return lines


def _throughput(tp: dict, t: dict) -> list[str]:
    length = "at full length" if tp["duration_s"] is None else f"cut to {tp['duration_s']} s"
    lines = ["## 4. Sweep throughput", "",
             f"`{tp['scenario']}` {length}, seeds 1..n, summary only, in worker processes "
             f"that start once and take run after run; {tp['note']}.", "",
             "| executor | workers | runs | s | runs/min | speed-up |", "|---|---|---|---|---|---|"]
    for c in tp["configs"].values():
        lines.append(f"| {c['executor']} | {c['workers']} | {c['runs']} | {c['seconds']:.1f} | "
                     f"{c['runs_per_minute']:.1f} | {c['speedup_vs_1_worker']:.2f}× |")
    w = tp["worker_startup"]
    lines += ["", f"One worker process on its own: importing the package takes "
                  f"{w['imports_seconds']:.2f} s; its first run takes "
                  f"{w['first_run_seconds']:.2f} s against {w['later_run_seconds']:.2f} s "
                  f"for the later ones ({w['first_run_extra_seconds']:.2f} s more: numba "
                  "loads its cached kernels, lazy imports, SUMO's first start)."]
    return [*lines, ""]


def _crowd(c: dict) -> list[str]:
    a = c["anonymous"]
    lines = ["## 3b. A scene with many pedestrians (real SUMO)", "",
             f"`{c['scenario']}`: {c['pedestrians']} pedestrians, median of {c['repeats']} "
             "run(s) of each, every per-step check on, the recorder included; labelled and "
             "anonymous detections and bare SUMO (through `SumoWorld`, the labelled run's "
             "steps) run side by side.", "",
             "| detections | steps | ms per step | / labelled | / bare SUMO |",
             "|---|---|---|---|---|",
             f"| labelled | {c['steps']} | {c['us_per_step'] / 1000:.1f} | – | "
             f"{c['ratio_to_bare']:.0f}× |",
             f"| anonymous | {a['steps']} | {a['us_per_step'] / 1000:.1f} | "
             f"{a['ratio_to_labelled']:.2f}× | {a['us_per_step'] / c['bare_us_per_step']:.0f}× |",
             "", f"Bare SUMO on the same scene: {c['bare_us_per_step'] / 1000:.2f} ms per step.",
             ""]
    for name, stages in (("labelled", c["stages_us"]), ("anonymous", a["stages_us"])):
        text = ", ".join(f"{stage} {us / 1000:.1f}" for stage, us in stages.items())
        lines += [f"Stages, {name} (ms per step): {text}.", ""]
    return lines


def _cluster(c: dict) -> list[str]:
    rows = "identical" if c["rows_identical"] else \
        f"DIFFERENT in {len(c['rows_different'])}+ runs, e.g. {c['rows_different'][0]}"
    lines = ["## 4b. A sweep on a Dask cluster", "",
             f"`{c['scenario']}` cut to {c['duration_s']} s, seeds 1..{c['runs']}, summary "
             f"only; {c['note']}. Every run's summary.json: {rows}.", "",
             "| executor | workers | runs | s | runs/min |", "|---|---|---|---|---|"]
    executors = {"local pool": c["local"], "Dask cluster": c["dask_cluster"]}
    for name, e in executors.items():
        lines.append(f"| {name} | {c['workers']} | {c['runs']} | {e['seconds']:.1f} | "
                     f"{e['runs_per_minute']:.1f} |")
    lines += ["", f"Where the CPU went while each executor ran (CPU seconds, user + system; "
                  f"{c['cores']} cores × the wall time is what the machine could give): the "
                  "run workers, the cluster's own processes (scheduler, nannies, Dask workers; "
                  "running beside the local pool too), this process (the pool's threads, the "
                  "Dask client), and the rest (other jobs, or idle).", "",
              "| executor | cores × wall | runs | cluster processes | this process | "
              "other or idle |", "|---|---|---|---|---|---|"]
    for name, e in executors.items():
        u = e["cpu_seconds"]
        lines.append(f"| {name} | {u['cores_wall']:.1f} | {u['runs']:.1f} | "
                     f"{u['cluster']:.1f} | {u['this_process']:.1f} | "
                     f"{u['other_or_idle']:.1f} |")
    return [*lines, ""]


def _tightness(tt: dict, t: dict) -> list[str]:
    lines = ["## 5. Tightness against the exact polygon filter", "",
             "Area of each set / area of the exact set (same strips, exact intersections and "
             "predictions with shapely, no reduction), over every node-step of the six "
             "scenarios' recorded streams.", "",
             "| local sets: gain | node-steps | mean | median | max |", "|---|---|---|---|---|"]
    for k, v in tt["local"].items():
        lines.append(f"| `{_cell(k)}` | {v['count']} | {_f(v.get('mean'), 3)} | "
                     f"{_f(v.get('median'), 3)} | {_f(v.get('max'), 3)} |")
    lines += ["", "| fused at the bus: gain \\| fusion | steps | mean | median | max |",
              "|---|---|---|---|---|"]
    for k, v in tt["fused"].items():
        lines.append(f"| `{_cell(k)}` | {v['count']} | {_f(v.get('mean'), 3)} | "
                     f"{_f(v.get('median'), 3)} | {_f(v.get('max'), 3)} |")
    lines += ["", f"Best local: `{tt['best_local']}`; best fused: `{_cell(tt['best_fused'])}`. "
              "The default (correction and fusion) is `enclose`, because it is the tightest: "
              "it intersects exactly as a 2-D polygon and encloses that in a zonotope along the "
              "polygon's edge directions, keeping the `volume` result (the smallest input) "
              "where that is smaller (`docs/method.md`); its price is in items 1 and 2 (the "
              "`enclose` rows against `volume`). "
              "Of the paper's Proposition 1 gains, `volume` is the exact area-optimal "
              "strip-by-strip update (2-D closed form, equal to `cvxpy-volume` at a fraction of "
              "its cost) and never larger than `frobenius`; of the fusions built on "
              "Proposition 2, only `strips` can go below the smallest input.", ""]
    return lines


def _arrivals(a: dict) -> list[str]:
    lines = ["## 5b. Decision tightness: earliest arrivals against an exact reference", "",
             "At every step, for every conflict zone ahead, the controller's earliest arrival "
             "of a pedestrian beside a slow reference computed from the same regions with "
             "exact shapely distances to the zone's exact ground, the jitter subtracted once "
             "from a path region and twice from a position region (`benchmarks/arrivals.py`). "
             "Later than the reference would be unsound; the ratio of the means says how much "
             "earlier it is on average, the shortfall the most at one zone-step.", "",
             "| scenario | zone-steps | later | controller / reference | within 10 s | "
             "largest shortfall (s) | collisions | violations |",
             "|---|---|---|---|---|---|---|---|"]
    for name, f in a["scenarios"].items():
        lines.append(f"| {name} | {f['zone_steps']:,} | {f['later_than_reference']} | "
                     f"{_f(f['ratio_of_means'], 4)} | {_f(f['ratio_of_means_within_horizon'], 4)}"
                     f" | {f['earliest_shortfall_s']:.3f} | {f['collisions']} | "
                     f"{f['containment_violations']} |")
    return [*lines, ""]


def _soundness(s: dict) -> list[str]:
    return ["## 6. Soundness campaign", "",
            f"**{s['violations']} violations in {s['node_steps']:,} node-steps** "
            f"({s['streams']} synthetic streams of {s['steps_per_stream']} steps; noise bounds "
            f"{s['noise_bounds_m']} m; noise {', '.join(s['noise_kinds'])} "
            f"({', '.join(f'{k}: {v:,}' for k, v in s['node_steps_by_noise_kind'].items())} "
            f"node-steps); gains {', '.join(s['gain_methods'])}; fusions "
            f"{', '.join(s['fusion_methods'])}).", "",
            "A node-step is one set at one step: each of three nodes' local set and the bus's "
            "fused set. The path moves on the speed bound 40 % of the steps, the jitter sits "
            "on its bound 40 % of the steps, worst-case noise puts every component on its "
            "bound. Each set is re-checked by a scipy HiGHS LP on G and c (block-diagonal "
            "batches, a failing batch re-checked one by one), not `Zonotope.contains`: the "
            "path set must hold the path point and the position set the measured position.",
            ""]


def _baseline(b: dict) -> list[str]:
    tot = b["open_loop_total"]
    lines = ["## 7. Kalman-filter baseline", "",
             "The KF (`sse_cosim.estimation.kalman`) gets the same strips as the zonotopes "
             "(bounds as Gaussian noise with sigma = bound / 3; process box likewise), from "
             "every node at the step they are taken (no V2X delay). Its region is the 3-sigma "
             "ellipse grown by the jitter.", "",
             f"Open loop (the pedestrian scenarios' recorded streams): the ellipse misses the "
             f"pedestrian in **{tot['kf_misses']} of {tot['steps']} steps "
             f"({100 * (tot['kf_miss_share'] or 0):.1f} %)**; the fused zonotope in "
             f"{tot['zonotope_misses']}.", "",
             "| scenario | steps | KF misses | zonotope misses |", "|---|---|---|---|"]
    for name, v in b["open_loop"].items():
        lines.append(f"| {name} | {v['steps']} | {v['kf_misses']} | {v['zonotope_misses']} |")
    lines += ["", "Closed loop (`estimator.filter = \"kalman\"`: the controller uses the ellipses "
              "instead of the refined zonotopes):", "",
              "| scenario | filter | average speed (m/s) | min distance (m) | misses | "
              "collisions |", "|---|---|---|---|---|---|"]
    for name, v in b["closed_loop"].items():
        k, z = v["kalman"], v["zonotope"]
        lines.append(f"| {name} | zonotope | {_f(z['average_speed_mps'], 2)} | "
                     f"{_f(z['min_distance_m'], 2)} | {z['containment_violations']} | "
                     f"{z['collisions']} |")
        lines.append(f"| {name} | kalman | {_f(k['average_speed_mps'], 2)} | "
                     f"{_f(k['min_distance_m'], 2)} | {k['ellipse_misses']} of "
                     f"{k['steps_with_region']} | {k['collisions']} |")
    return [*lines, ""]


def _campaign(r: dict) -> list[str]:
    c, speedup = r["campaign"], _speedup(r)
    length = "at full length" if c["duration_s"] is None else f"cut to {c['duration_s']} s"
    used = (f"item 4's speed-up of two local workers, {speedup:.2f}×" if speedup is not None
            else "two workers counted as twice one (item 4 not run)")
    lines = ["## 8. The safety campaign, projected", "",
             f"`{c['campaign']}`{' ([quick] subset)' if c['quick'] else ''} planned as "
             f"`sse-cosim safety` plans it: {c['runs']:,} runs, {c['not_feasible']:,} "
             f"combinations not feasible (not run), planned in {c['planning_seconds']:.0f} s. "
             f"One run of each scenario (the middle of its list, {length}, summary only) timed "
             "in one worker after a warm-up run; each includes loading its network, which the "
             "campaign pays once per worker, so the projection errs long.", "",
             "| scenario | runs | one run (s) | runs × one run (min) | share |",
             "|---|---|---|---|---|"]
    total = sum(s["serial_minutes"] for s in c["scenarios"].values())
    for stem, s in c["scenarios"].items():
        lines.append(f"| {stem} | {s['runs']} | {s['run_seconds']:.1f} | "
                     f"{s['serial_minutes']:.1f} | {100 * s['serial_minutes'] / total:.0f} % |")
    lines += ["", f"Projected wall time of `make safety` on two cores: planning + "
                  f"{total:.1f} min on one worker / {used} = **{_projected(r):.0f} min**.", ""]
    return lines


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell (``|`` escaped)."""
    return text.replace("|", "\\|")
