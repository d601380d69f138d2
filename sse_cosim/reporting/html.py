"""``report.html``: one self-contained page built from run folders, without simulating.

Figures are embedded as base64 PNG and the style sheet is inline, so the file can be
mailed or archived alone. The page holds Table I and the speed profiles (paper Fig. 6),
the set sizes at the first shared fusion (Fig. 7), each single run's key moments (Fig. 5) and
set areas with a link to its replay, and every sweep's parameters, failures, plots, table and
replays. Each section shows the command that made its numbers: ``sse-cosim run`` per run, the
recorded ``sse-cosim sweep`` per sweep.
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import shlex
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sse_cosim import __version__
from sse_cosim.errors import UserError
from sse_cosim.files import GZIP_SUFFIX, write_text_atomic
from sse_cosim.reporting.falsify_report import FALSIFY_PLAN
from sse_cosim.reporting.outputs import KEY_MOMENTS
from sse_cosim.reporting.paper import (
    DIFFERENCE_NOTE,
    POLICY_TITLES,
    TABLE1_FILES,
    RunFolder,
    fault_table,
    fig7,
    read_run_folders,
    table1,
    write_paper_report,
)
from sse_cosim.reporting.replay import replay_href
from sse_cosim.reporting.safety_report import SAFETY_PLAN
from sse_cosim.reporting.sweep_report import (
    PLOTTED,
    FigureUncertainty,
    SweepFolder,
    figure_label,
    find_sweeps,
    summary_figures,
    summary_table,
    sweep_table,
    uncertainty,
    write_sweep_report,
)

REPORT = "report.html"
TABLE_ROWS_MAX = 500  # longer tables are cut (the CSV files have every row)
FAILURES_MAX = 50
RUN_FIGURES = ((KEY_MOMENTS, "Key moments (paper Fig. 5)"),
               ("set_areas.png", "Set areas over time"))
CARD_FIGURES = (
    "average_speed_mps", "travel_time_s", "min_distance_bus_pedestrian_m",
    "first_detection_fused_bus_to_crossing_m", "containment_violations", "collisions",
)


def write_report(folders: Sequence[Path], out_dir: Path, command: str) -> list[Path]:
    """Rebuild every table and figure from the runs and sweeps under ``folders``, then write
    ``out_dir/report.html``; returns the files written.

    Sweep outputs are rebuilt inside each sweep folder; Table I and Fig. 7 (from the runs
    that are not part of a sweep) go to ``out_dir``.
    """
    sweeps = find_sweeps(folders)
    runs = single_runs(folders, sweeps)
    if not runs and not sweeps:
        raise UserError(", ".join(map(str, folders)), "", "holds no finished run or sweep",
                        "name folders written by `sse-cosim run`, `batch` or `sweep`")
    written = [path for sweep in sweeps for path in write_sweep_report(sweep.path)]
    written += write_paper_report(out_dir, runs)
    page = render_report(runs, sweeps, out_dir, command)
    written.append(write_text_atomic(out_dir / REPORT, page))
    return written


def single_runs(folders: Sequence[Path], sweeps: Sequence[SweepFolder]) -> list[RunFolder]:
    """Finished runs under ``folders`` that belong to no sweep, safety campaign or falsify
    search (which have reports of their own), each once. A campaign an older version wrote,
    its plan not yet gzipped, is one too (its own report asks for the plan gzipped)."""
    plans = (SAFETY_PLAN, SAFETY_PLAN.removesuffix(GZIP_SUFFIX), FALSIFY_PLAN)
    campaigns = [plan.parent for root in folders for name in plans
                 for plan in Path(root).rglob(name)]
    roots = [folder.resolve() for folder in [*(sweep.path for sweep in sweeps), *campaigns]]
    unique = {run.path.resolve(): run for run in read_run_folders(folders)}
    return [run for path, run in unique.items()
            if not any(path.is_relative_to(root) for root in roots)]


def render_report(runs: Sequence[RunFolder], sweeps: Sequence[SweepFolder], out_dir: Path,
                  command: str) -> str:
    """The whole page as one HTML string."""
    sections = [_paper_section(runs, out_dir), _runs_section(runs, out_dir),
                *(_sweep_section(sweep, i, out_dir) for i, sweep in enumerate(sweeps, 1))]
    sections = [s for s in sections if s]
    toc = "".join(f'<li><a href="#{anchor}">{html.escape(title)}</a></li>'
                  for anchor, title in _headings(runs, sweeps))
    return _PAGE.format(
        css=_CSS, version=__version__, command=_command(command),
        toc=f"<nav><ol>{toc}</ol></nav>", body="\n".join(sections),
    )


def _headings(runs: Sequence[RunFolder],
              sweeps: Sequence[SweepFolder]) -> Iterator[tuple[str, str]]:
    if runs:
        yield "table1", "Table I: average bus speed"
        yield "fig7", "Fig. 7: set sizes at the first shared fusion"
        if any(r.faults for r in runs):
            yield "faults", "Injected faults"
        yield "runs", "Runs"
    for i, sweep in enumerate(sweeps, 1):
        yield f"sweep{i}", f"Sweep: {_shown(sweep.path)}"


def _table1_part(runs: Sequence[RunFolder], out_dir: Path, policy: str) -> list[str]:
    """Table I and the speed profiles of the runs under ``policy`` (nothing without any)."""
    table = table1(runs, policy)
    if table.empty:
        return []
    marked = {
        (i, "average_speed_mps") for i, row in table.iterrows()
        if pd.notna(row["paper_average_speed"])
        and abs(row["average_speed_mps"] - row["paper_average_speed"])
        > DIFFERENCE_NOTE * row["paper_average_speed"]
    }
    suffix = TABLE1_FILES[policy]
    return [f"<h3>{POLICY_TITLES[policy].capitalize()}</h3>", _table(table, marked),
            _image(out_dir / f"speed_profiles{suffix}.png", "Bus speed profiles (paper Fig. 6)")]


def _paper_section(runs: Sequence[RunFolder], out_dir: Path) -> str:
    if not runs:
        return ""
    sizes = fig7(runs)
    return "\n".join([
        '<h2 id="table1">Table I: average bus speed</h2>',
        "<p>Our runs beside the paper's Table I (nominal speed 20 m/s), under each speed "
        "policy (docs/controller.md), with the speed profiles (paper Fig. 6). Highlighted: "
        f"more than {DIFFERENCE_NOTE:.0%} away from the paper. Each run, with the command that "
        'reproduces it, is listed under <a href="#runs">Runs</a>.</p>',
        *(part for policy in TABLE1_FILES for part in _table1_part(runs, out_dir, policy)),
        '<h2 id="fig7">Fig. 7: set sizes at the first shared fusion</h2>',
        _table(sizes) + _image(out_dir / "fig7_set_sizes.png", "Set sizes")
        if not sizes.empty else "<p>No run with a pedestrian and shared estimates.</p>",
        _faults_section(runs),
    ])


def _faults_section(runs: Sequence[RunFolder]) -> str:
    faults = fault_table(runs)
    if faults.empty:
        return ""
    return "\n".join([
        '<h2 id="faults">Injected faults</h2>',
        "<p>Per injected fault: the steps from its start to its flag (empty: never flagged, "
        "as for faults within the bounds or a shrunk sender, which consistency cannot "
        "reveal), and the fused set's misses after the flag. See docs/faults.md.</p>",
        _table(faults),
    ])


def _runs_section(runs: Sequence[RunFolder], out_dir: Path) -> str:
    if not runs:
        return ""
    cards = []
    for run in sorted(runs, key=lambda r: (r.name, not r.pedestrian, str(r.path))):
        flat = summary_figures(run.summary)
        facts = "".join(f"<tr><th>{html.escape(figure_label(f))}</th><td>{_cell(flat[f])}</td></tr>"
                        for f in CARD_FIGURES)
        images = "".join(_image(run.path / name, title) for name, title in RUN_FIGURES)
        cards.append(
            f'<div class="card"><h3>{html.escape(run.label)}</h3>'
            f"<p class=\"where\">{html.escape(_shown(run.path))}</p>"
            f"{_command(_run_command(run.summary.get('source', '?'), {}, run.path))}"
            f"{_replay_link(run.path, out_dir, 'Replay this run', run.summary)}"
            f'<table class="facts">{facts}</table>{images}</div>'
        )
    return ('<h2 id="runs">Runs</h2><p>Every run outside a sweep; scenario.json in each '
            "folder holds the resolved scenario.</p>"
            f'<div class="cards">{"".join(cards)}</div>')


def _replay_link(folder: Path, out_dir: Path, text: str,
                 summary: Mapping[str, Any] | None = None) -> str:
    """A link to ``folder``'s replay, relative to the report in ``out_dir``, at the run's key
    moment (its ``summary``'s first detection); nothing if the run kept no replay (a
    summaries-only sweep)."""
    href = replay_href(folder, out_dir, summary)
    return "" if href is None else \
        f'<a class="replay" href="{html.escape(href)}">{html.escape(text)}</a>'


def _summary(sweep: SweepFolder, run: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """A sweep run's summary; None while it has none (failed, not finished)."""
    outcome = sweep.outcome(run)
    return None if outcome is None else outcome.summary


def _sweep_replays(sweep: SweepFolder, out_dir: Path) -> str:
    """Links to the replays of the sweep's runs (nothing if none kept one)."""
    links = [link for run in sweep.runs
             if (link := _replay_link(sweep.run_folder(run["key"]), out_dir, run["key"],
                                      _summary(sweep, run)))]
    if not links:
        return ""
    return (f"<details><summary>Replays ({len(links)} runs)</summary>"
            f'<p class="replays">{" ".join(links)}</p></details>')


def _sweep_section(sweep: SweepFolder, number: int, out_dir: Path) -> str:
    table = sweep_table(sweep)
    counts = table["status"].value_counts()
    seeds = sweep.plan.get("seeds")
    parameters = pd.DataFrame(
        [{"column": p["column"], "path": p["path"],
          "values": ", ".join(json.dumps(v) for v in p["values"])} for p in sweep.parameters]
    )
    images = "".join(_image(sweep.path / f"sweep_{figure}.png", figure_label(figure))
                     for figure in PLOTTED)
    every = table.assign(command=[
        _run_command(run["source"], run["overrides"], sweep.run_folder(run["key"]))
        for run in sweep.runs
    ])
    return "\n".join([
        f'<h2 id="sweep{number}">Sweep: {html.escape(_shown(sweep.path))}</h2>',
        _command(sweep.plan.get("command", "")),
        f"<p>{len(table)} runs: {counts.get('ok', 0)} finished, {counts.get('failed', 0)} "
        f"failed, {counts.get('missing', 0)} not run yet. Seeds: "
        f"{html.escape(json.dumps(seeds)) if seeds else 'each scenario its own'}. "
        "List values are plotted at their largest component.</p>",
        _table(parameters) if not parameters.empty else "<p>No swept parameter.</p>",
        _failures(table[table["status"] != "ok"]),
        "<h3>Summary (runs of one combination combined)</h3>",
        _table(summary_table(table, sweep.columns)),
        _uncertainty_part(uncertainty(sweep, table)),
        f'<div class="figures">{images}</div>',
        "<details><summary>Every run (sweep.csv, with the command that reproduces it)"
        f'</summary><div class="scroll">{_table(every)}</div></details>',
        _sweep_replays(sweep, out_dir),
    ])


def _uncertainty_part(items: Sequence[FigureUncertainty]) -> str:
    """Each responding figure's mean and 95 % interval over seeds, and which differences
    between neighbouring levels exceed the seeds' spread (sweep_uncertainty.md's content)."""
    parts = ["<h3>What the seeds leave uncertain</h3>",
             "<p>Per combination: the runs (one per seed), the mean and Student's 95 % "
             "confidence interval of the mean. Between neighbouring levels: the difference "
             "of the means with Welch's 95 % interval; it exceeds the seeds' spread where "
             "that interval leaves out zero (also in sweep_uncertainty.md).</p>"]
    for item in items:
        label = figure_label(item.figure)
        exceed = [d for d in item.differences if d.exceeds]
        lines = "".join(f'<li{" class=off" if d.exceeds else ""}>{html.escape(d.line(label))}'
                        "</li>" for d in item.differences)
        parts += [f"<h4>{html.escape(label)}</h4>", _table(item.table),
                  f"<p>{len(exceed)} of {len(item.differences)} differences between "
                  "neighbouring levels exceed the seeds' spread.</p>",
                  f"<details><summary>Every difference</summary><ul>{lines}</ul></details>"]
    return "\n".join(parts)


def _failures(failed: pd.DataFrame) -> str:
    items = [f"<li><code>{html.escape(row.key)}</code> ({row.status}): "
             f"{html.escape(row.error)}</li>" for row in failed.head(FAILURES_MAX).itertuples()]
    if len(failed) > FAILURES_MAX:
        items.append(f"<li>... and {len(failed) - FAILURES_MAX} more (see sweep.csv)</li>")
    return f'<ul class="fail">{"".join(items)}</ul>' if items else ""


def _run_command(source: str, overrides: Mapping[str, Any], folder: Path) -> str:
    sets = [part for path, value in overrides.items()
            for part in ("--set", f"{path}={json.dumps(value)}")]
    return shlex.join(["sse-cosim", "run", _shown(source), *sets, "--out", _shown(folder)])


def _table(frame: pd.DataFrame, marked: Iterable[tuple[Any, str]] = ()) -> str:
    """A plain HTML table (at most ``TABLE_ROWS_MAX`` rows); cells in ``marked``
    (index, column) are highlighted."""
    marked = set(marked)
    head = "".join(f"<th>{html.escape(figure_label(str(c)))}</th>" for c in frame.columns)
    rows = []
    for index, row in frame.head(TABLE_ROWS_MAX).iterrows():
        cells = "".join(
            f'<td{" class=off" if (index, column) in marked else ""}>{_cell(value)}</td>'
            for column, value in row.items()
        )
        rows.append(f"<tr>{cells}</tr>")
    more = (f"<p>First {TABLE_ROWS_MAX} of {len(frame)} rows; the CSV file has them all.</p>"
            if len(frame) > TABLE_ROWS_MAX else "")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>{more}"


def _cell(value: Any) -> str:
    if value is None or value is pd.NA or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if isinstance(value, bool | np.bool_):
        return "✓" if value else "–"
    if isinstance(value, float):
        return f"{value:.4g}"
    text = html.escape(str(value))
    return f"<code>{text}</code>" if text.startswith("sse-cosim ") else text


def _image(path: Path, alt: str) -> str:
    """``path`` embedded as a base64 PNG; nothing if the figure does not exist."""
    if not path.is_file():
        return ""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def _command(command: str) -> str:
    return f'<pre class="cmd"><code>$ {html.escape(command)}</code></pre>' if command else ""


def _shown(path: str | os.PathLike[str]) -> str:
    """``path`` relative to the working folder when it lies inside it."""
    path = Path(path)
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1d2330;
       max-width: 1180px; margin: 2rem auto; padding: 0 1.2rem; line-height: 1.45; }
h1 { font-size: 1.7rem; margin-bottom: .2rem; }
h2 { margin-top: 2.6rem; padding-bottom: .25rem; border-bottom: 2px solid #e4e7ee; }
h3 { margin: 1.4rem 0 .4rem; font-size: 1.05rem; }
nav ol { columns: 2; font-size: .92rem; }
a { color: #2856b6; text-decoration: none; }
table { border-collapse: collapse; font-size: .84rem; margin: .7rem 0; }
th, td { padding: .32rem .65rem; border-bottom: 1px solid #e9ebf0; text-align: right; }
thead th { background: #f4f6fa; text-align: center; font-weight: 600; }
td:first-child, th:first-child { text-align: left; }
tbody tr:hover td { background: #f8f9fc; }
td.off, li.off { background: #fff1c2; font-weight: 600; }
code { font-family: ui-monospace, Menlo, Consolas, monospace; font-size: .82em; }
td code { white-space: nowrap; }
pre.cmd { background: #1d2330; color: #e8ecf5; padding: .55rem .8rem; border-radius: 6px;
          overflow-x: auto; font-size: .9rem; }
img { max-width: 100%; height: auto; display: block; margin: .7rem 0; }
.cards { display: grid; grid-template-columns: repeat(auto-fill, minmax(520px, 1fr));
         gap: 1rem; }
.card { border: 1px solid #e4e7ee; border-radius: 8px; padding: .3rem 1rem .6rem; }
.card h3 { margin-top: .6rem; }
.where { color: #687087; font-size: .85rem; margin: 0; }
table.facts th { text-align: left; font-weight: normal; background: none; }
ul.fail { color: #a3132b; font-size: .9rem; }
.scroll { overflow-x: auto; }
.figures { display: grid; grid-template-columns: repeat(auto-fill, minmax(540px, 1fr));
           gap: .5rem 1rem; }
a.replay { display: inline-block; margin: .2rem 0 .4rem; font-weight: 600; }
p.replays a { margin-right: .6rem; }
details summary { cursor: pointer; font-weight: 600; margin: 1rem 0 .4rem; }
footer { margin-top: 3rem; color: #687087; font-size: .85rem; }
"""

_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>sse-cosim report</title>
<style>{css}</style>
</head>
<body>
<h1>sse-cosim report</h1>
<p>Set-membership estimation in shared situational awareness: an automated bus, an occluded
zebra crossing and zonotopes shared over V2X, co-simulated in SUMO. Built from finished run
folders by:</p>
{command}
{toc}
{body}
<footer>sse-cosim {version}. Every figure is embedded; this file needs nothing else.</footer>
</body>
</html>
"""
