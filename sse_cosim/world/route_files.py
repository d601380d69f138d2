"""A scenario's own SUMO route files (``network.route_files``), checked before SUMO loads them.

SUMO loads them next to the route file the project writes (:mod:`sse_cosim.world.demand`):
their vehicles are in every snapshot (every footprint occludes the sensors), their persons are
pedestrians the nodes estimate, by person id. Pure Python (``xml.etree``); no SUMO process.

Determinism. One seed must give one run, so every type declared in a route file sets
``speedDev="0"`` and ``sigma="0"`` (SUMO's defaults draw a random speed factor per vehicle
and let drivers dawdle), and every vehicle, trip, flow, person and person flow names a
declared type or type distribution (SUMO's default types are not deterministic). Such a file
is refused, naming the file, the type and the fix. Random departures (``probability`` flows)
are drawn from SUMO's seed, which is the scenario's: they are deterministic too.

Persons exist from t = 0. The estimator assumes that a pedestrian nobody has detected has been
somewhere on walkable ground since the start (:mod:`sse_cosim.world.demand`); one appearing
later could appear where the sensors already saw nobody. So every person departs at 0 (it may
wait first: a ``<stop>`` as its first stage), and person flows, which depart persons over
time, are refused.

Ids. The project's own actors and types (``bus``, ``truck``, ``car``, ``pedestrian``) are
reserved: a route file may not reuse them.

Where persons walk. A person whose every stage is a walk given edge by edge (``<walk
edges="...">``) or a stop on an edge or lane walks those edges and the junctions between them
only: SUMO follows the listed edges. :attr:`RouteFiles.walked_edges` gathers them, so that the
walkers' jitter is measured where they walk (:mod:`sse_cosim.world.extent`). A walk SUMO
routes itself (``from``/``to``, a ``route`` or a stop's id), a ``personTrip`` or a ride may
take a person anywhere: then it is None.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from sse_cosim.errors import UserError

FIELD = "network.route_files"
TYPE_TAGS = ("vType", "vTypeDistribution")
DEMAND_TAGS = ("vehicle", "trip", "flow", "person")
DETERMINISTIC_ATTRIBUTES = ("speedDev", "sigma")


@dataclass(frozen=True)
class RouteFiles:
    """The checked route files: their ``paths`` (in the scenario's order), the ids of the
    vehicle and person types they declare (``type_ids``) and every edge their persons walk or
    stand on (``walked_edges``; None: a person SUMO routes itself, module docstring)."""

    paths: tuple[Path, ...]
    type_ids: frozenset[str]
    walked_edges: frozenset[str] | None = frozenset()


def read_route_files(paths: Sequence[str], reserved_ids: Iterable[str],
                     source: str) -> RouteFiles:
    """Parse and check every route file (see module docstring); a problem is a one-line
    :class:`UserError` naming ``source``, ``network.route_files`` and the file."""
    reserved = frozenset(reserved_ids)
    roots = [(Path(p), _parse(Path(p), source)) for p in paths]
    declared: set[str] = set()
    walked: set[str] | None = set()
    for path, root in roots:
        for element in root.iter():
            if element.tag in TYPE_TAGS:
                _check_type(path, element, reserved, source)
                declared.add(element.attrib["id"])
    for path, root in roots:
        for element in root.iter():
            if element.tag == "personFlow":
                raise UserError(source, FIELD, f"{path}: personFlow "
                                f"{element.attrib.get('id', '')!r} departs persons after t = 0, "
                                "where sensors may have seen nobody",
                                "write its persons out, each departing at 0")
            if element.tag in DEMAND_TAGS:
                _check_demand(path, element, declared, reserved, source)
            if element.tag == "person" and walked is not None:
                edges = person_edges(element)
                walked = None if edges is None else walked | edges
    return RouteFiles(tuple(path for path, _ in roots), frozenset(declared),
                      None if walked is None else frozenset(walked))


def person_edges(person: ET.Element) -> set[str] | None:
    """The edges a ``<person>`` walks or stands on, or None where SUMO may route it anywhere
    (module docstring)."""
    edges: set[str] = set()
    for stage in person:
        if stage.tag == "param":
            continue
        if stage.tag == "walk" and "edges" in stage.attrib:
            edges.update(stage.attrib["edges"].split())
        elif stage.tag == "stop" and ("edge" in stage.attrib or "lane" in stage.attrib):
            edges.add(stage.attrib.get("edge") or stage.attrib["lane"].rpartition("_")[0])
        else:
            return None
    return edges


def _parse(path: Path, source: str) -> ET.Element:
    if not path.is_file():
        raise UserError(source, FIELD, f"route file {str(path)!r} not found",
                        "fix the path (relative to the scenario file that sets it)")
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise UserError(source, FIELD, f"route file {str(path)!r} cannot be read ({exc})",
                        "give a SUMO route file (<routes> ... </routes>)") from None
    if root.tag != "routes":
        raise UserError(source, FIELD, f"{str(path)!r} is no SUMO route file (its root element "
                        f"is <{root.tag}>, not <routes>)", "give a .rou.xml file")
    return root


def _check_type(path: Path, element: ET.Element, reserved: frozenset[str], source: str) -> None:
    type_id = element.attrib.get("id")
    if not type_id:
        raise UserError(source, FIELD, f"{path}: a <{element.tag}> has no id", "give it an id")
    if type_id in reserved:
        raise UserError(source, FIELD, f"{path}: type id {type_id!r} is reserved for the "
                        "scenario's own actors", "rename the type")
    if element.tag != "vType":
        return
    for name in DETERMINISTIC_ATTRIBUTES:
        value = element.attrib.get(name)
        if value is None or _number(value) != 0.0:
            found = "leaves it unset (SUMO's default is random)" if value is None \
                else f"sets {name}={value!r}"
            raise UserError(source, FIELD, f"{path}: vType {type_id!r} {found}: the run would "
                            "not be deterministic",
                            'set speedDev="0" and sigma="0" on the type')


def _check_demand(path: Path, element: ET.Element, declared: set[str],
                  reserved: frozenset[str], source: str) -> None:
    demand_id = element.attrib.get("id", "")
    if demand_id in reserved:
        raise UserError(source, FIELD, f"{path}: {element.tag} id {demand_id!r} is reserved "
                        "for the scenario's own actors", "rename it")
    type_id = element.attrib.get("type")
    if type_id is None or type_id not in declared:
        problem = "names no type, so SUMO gives it a default type (not deterministic)" \
            if type_id is None else f"has type {type_id!r}, which no route file declares"
        raise UserError(source, FIELD, f"{path}: {element.tag} {demand_id!r} {problem}",
                        'declare a vType with speedDev="0" and sigma="0" and name it in type=')
    if element.tag == "person" and _number(element.attrib.get("depart", "")) != 0.0:
        raise UserError(source, FIELD, f"{path}: person {demand_id!r} departs at "
                        f"{element.attrib.get('depart')!r}, not at 0: it would appear where "
                        "sensors may have seen nobody",
                        'set depart="0" (a <stop> first lets it wait)')


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None
