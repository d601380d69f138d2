"""``benchmarks.md`` from the results dictionary of :func:`benchmarks.run.run_all`."""

from __future__ import annotations

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
    if "soundness" in r:
        lines += _soundness(r["soundness"])
    if "baseline" in r:
        lines += _baseline(r["baseline"])
    if r.get("loop_cost", {}).get("profile_default_gain"):
        lines += ["## Profile of one run (S3 with the pedestrian, default methods)", "",
                  "cProfile, cumulative time; the stage table above attributes the same time "
                  "to the loop's stages.", "", "```",
                  r["loop_cost"]["profile_default_gain"], "```", ""]
    return "\n".join(lines) + "\n"


def _summary(r: dict, t: dict) -> list[str]:
    rows = []
    budgets: dict[str, str] = {}  # a cost-per-step row's name -> what must go to meet it
    loop = r.get("loop_cost", {}).get("configs", {})
    if "a_frobenius" in loop:
        for name, config, key in (("1a co-sim (frobenius) / bare SUMO", "a_frobenius",
                                   "loop_a_ratio_to_bare"),
                                  ("1 co-sim (default methods) / bare SUMO", "default_enclose",
                                   "loop_default_ratio_to_bare")):
            if config not in loop:
                continue
            ratio = loop[config]["ratio_to_bare"]
            rows.append((name, f"{ratio:.1f}×", f"≤ {t[key]:.0f}×", ratio <= t[key]))
            budgets[name] = _budget(loop[config], t[key], r["loop_cost"]["bare_us_per_step"])
        for name, c in loop.items():
            if name.startswith("b_"):
                rows.append((f"1b co-sim ({c['gain_method']}) / (a)", f"{c['ratio_to_a']:.1f}×",
                             f"≤ {t['loop_b_ratio_to_a']:.0f}×",
                             c["ratio_to_a"] <= t["loop_b_ratio_to_a"]))
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


def _budget(config: dict, ratio: float, bare_us: float) -> str:
    """For a cost-per-step target of at most ``ratio`` × bare SUMO (``bare_us`` per step):
    how much of ``config``'s step must go to meet it, against its largest stage."""
    allowed = ratio * bare_us
    excess = config["us_per_step"] - allowed
    stage, largest = max(config["stages_us"].items(), key=lambda item: item[1])
    return (f" At ≤ {ratio:g}× a step may take {allowed:,.0f} µs; it takes "
            f"{config['us_per_step']:,.0f}, so {excess:,.0f} µs must go "
            f"({'more' if excess > largest else 'less'} than its largest stage, `{stage}`, "
            f"at {largest:,.0f} µs).")


NEXT_STEPS = {
    "1": "the stage table (item 1) and the profile at the end of this file: most of a step "
         "is shapely's overlay calls (buffer, intersection, difference, union) in the "
         "occupancy and sensor stages, each on small polygons, and the rest is spread over "
         "every stage. Next: a raster over-approximation of the unobserved area and of the "
         "known regions (the occupancy stage) and of the sensors' visible and hidden regions "
         "(in the geometry stage), with a test that proves it covers the exact polygons on "
         "random shapes; the controller and the recorder would then read rasters.",
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
          "sensors' strips. Next: the raster over-approximation of item 1, for every "
          "pedestrian's region at once.",
    "4 Dask cluster": "item 4b, its CPU table: the cluster's own processes (scheduler, "
                      "nannies, Dask workers) take CPU time beside the runs on the same 2 "
                      "cores, while the local pool pays its workers' start-up in each half. "
                      "Next: run the cluster's scheduler off the workers' cores, as on a real "
                      "cluster, or quiet its per-worker bookkeeping (heartbeats, memory "
                      "monitor).",
    "4 sweep": "item 4: the speed-up of the whole batch, each worker's start-up inside it "
               "(measured alone under the table: imports, then numba loading its cached "
               "kernels and SUMO's first start in the first run); on 2 cores the main "
               "process, and any other job on the machine, also take their share beside two "
               "workers. Next: a shorter start-up (fewer kernels for numba to load, fewer "
               "imports in the worker), or workers that stay up from one batch to the next.",
}
"""By the start of a target's name in the summary: where its profile is and the next step."""


def _loop(loop: dict, t: dict) -> list[str]:
    stages = list(next(iter(loop["configs"].values()))["stages_us"])
    lines = [
        "## 1. Cost per step against bare SUMO",
        "",
        f"`{loop['scenario']}`, {loop['steps']} steps of 0.1 s, {loop['repeats']} repeats "
        f"(median). Fusion method `{loop['fusion_method']}` (the default) in every "
        "configuration, whatever the nodes' correction. Bare SUMO: the same network, routes "
        "and steps through `SumoWorld` (the "
        "snapshot built every step), the bus commanded to its nominal speed, no sensor layer: "
        f"**{loop['bare_us_per_step']:.0f} µs/step** (real-time factor "
        f"{loop['bare_real_time_factor']:,.0f}). The co-simulation includes the recorder "
        "(trace rows, containment checks), not the file writing at the end of a run.",
        "",
        "| configuration | gain | µs/step | / bare | / (a) | real-time factor |",
        "|---|---|---|---|---|---|",
    ]
    for name, c in loop["configs"].items():
        lines.append(f"| {name} | `{c['gain_method']}` | {c['us_per_step']:,.0f} | "
                     f"{c['ratio_to_bare']:.1f}× | {_f(c.get('ratio_to_a'), 1)} | "
                     f"{c['real_time_factor']:.1f} |")
    lines += ["", "µs per step of each stage (`sse_cosim.runner.timing.StageTimer`):", "",
              "| configuration | " + " | ".join(stages) + " |",
              "|---|" + "---|" * len(stages)]
    for name, c in loop["configs"].items():
        lines.append(f"| {name} | " + " | ".join(f"{c['stages_us'][s]:,.0f}" for s in stages)
                     + " |")
    lines += ["", "Stages: `sumo` SUMO step and snapshot; `geometry` sensors (line of sight, "
              "visible/occluded regions, strips); `local_fusion` every node's observer; "
              "`sharing_fusion` V2X, consistency screen and fusion at the bus; `occupancy` "
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
    stages = ", ".join(f"{name} {us / 1000:.1f}" for name, us in c["stages_us"].items())
    return ["## 3b. A scene with many pedestrians (real SUMO)", "",
            f"`{c['scenario']}`: {c['pedestrians']} pedestrians, {c['steps']} steps, median of "
            f"{c['repeats']} run(s), every per-step check on.", "",
            "| ms per step | bare SUMO, same scene (ms) | ratio |", "|---|---|---|",
            f"| {c['us_per_step'] / 1000:.1f} | {c['bare_us_per_step'] / 1000:.2f} | "
            f"{c['ratio_to_bare']:.0f}× |", "", f"Stages (ms per step): {stages}.", ""]


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


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell (``|`` escaped)."""
    return text.replace("|", "\\|")
