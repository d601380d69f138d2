"""The scenario's SUMO network: an existing ``.net.xml``, or built from plain-XML sources by
netconvert, cached by content.

``scenario_net_path(network, source)`` is the ``.net.xml`` of a scenario's ``[network]``: its
``net_file`` (checked to be a readable SUMO network; used as it is, never rebuilt), or the
network built from its ``sources_dir``.

``build_network(sources_dir)`` returns the path of a ``.net.xml`` built from the sources in
``sources_dir`` (``*.nod.xml``, ``*.edg.xml``, optionally ``*.con.xml``, ``*.typ.xml`` and a
``netconvert.cfg`` options file). The result lives in ``<sources_dir>/build/<key>/road.net.xml``
where ``key`` hashes the sources' names and contents and netconvert's version: unchanged
sources reuse the built net, any change builds a new one. A build goes into a temporary folder
that is renamed into place only when netconvert succeeded, so parallel processes and crashes
never leave a half-written net behind. The ``.net.xml`` is never edited by hand.
"""

from __future__ import annotations

import functools
import gzip
import hashlib
import os
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

from sse_cosim.errors import UserError
from sse_cosim.files import write_text_atomic

if TYPE_CHECKING:  # the schema is only needed for type checking
    from sse_cosim.scenario.model import Network

NET_FILE_NAME = "road.net.xml"
BUILD_DIR_NAME = "build"
OPTIONS_FILE_NAME = "netconvert.cfg"
# suffix -> netconvert option; the first two are required, one file each at most.
SOURCE_KINDS = {
    ".nod.xml": "--node-files",
    ".edg.xml": "--edge-files",
    ".con.xml": "--connection-files",
    ".typ.xml": "--type-files",
}
REQUIRED_KINDS = (".nod.xml", ".edg.xml")
NETCONVERT_TIMEOUT_S = 120


class NetworkBuildError(UserError):
    """netconvert rejected the sources: the network does not build (a run reports it as a
    simulation failure naming the scenario)."""


def scenario_net_path(network: Network, source: str) -> Path:
    """The ``.net.xml`` of a scenario's ``[network]`` (see module docstring).

    A missing or unreadable ``net_file``, or sources that cannot be found, are a
    :class:`UserError` naming ``source`` and the field; sources that netconvert rejects are a
    :class:`NetworkBuildError`.
    """
    if network.net_file is not None:
        return check_net_file(Path(network.net_file), source)
    sources = str(network.sources_dir)
    try:
        return build_network(sources)
    except NetworkBuildError:
        raise
    except UserError as exc:
        if exc.source != sources:
            raise
        raise UserError(source, "network.sources_dir", f"{sources}: {exc.problem}",
                        exc.fix) from None


def check_net_file(path: Path, source: str) -> Path:
    """``path`` if it is a readable SUMO network (its root element is ``<net>``; gzipped when
    its name ends with ``.gz``, as osmWebWizard writes it)."""
    fix = ("point network.net_file at a SUMO .net.xml (relative to the scenario file that sets "
           "it; given with --set, relative to the working directory), or use "
           "network.sources_dir for plain-XML sources")
    if not path.is_file():
        raise UserError(source, "network.net_file", f"{str(path)!r} not found", fix)
    try:
        with gzip.open(path) if path.name.endswith(".gz") else path.open("rb") as stream:
            _, root = next(ET.iterparse(stream, events=("start",)))
    except (ET.ParseError, OSError, EOFError, StopIteration) as exc:
        raise UserError(source, "network.net_file", f"{str(path)!r} cannot be read ({exc})",
                        fix) from None
    if root.tag != "net":
        raise UserError(source, "network.net_file", f"{str(path)!r} is no SUMO network (its "
                        f"root element is <{root.tag}>, not <net>)", fix)
    return path


def build_network(sources_dir: str | os.PathLike[str]) -> Path:
    """The ``.net.xml`` built from the sources in ``sources_dir`` (built or reused from cache)."""
    sources_dir = Path(sources_dir)
    sources = network_sources(sources_dir)
    netconvert = netconvert_path()
    key = _cache_key(sources, netconvert_version())
    target_dir = sources_dir / BUILD_DIR_NAME / key
    net_path = target_dir / NET_FILE_NAME
    if net_path.is_file():
        return net_path
    build_root = target_dir.parent
    try:
        build_root.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(str(sources_dir), "", f"cannot create the build folder ({exc})",
                        "make the network sources folder writable") from None
    tmp_dir = Path(tempfile.mkdtemp(prefix=f".{key}.", suffix=".part", dir=build_root))
    try:
        _run_netconvert(netconvert, sources, tmp_dir / NET_FILE_NAME, sources_dir)
        try:
            os.rename(tmp_dir, target_dir)
        except OSError:
            # Another process finished the same build first; its result is identical.
            if not net_path.is_file():
                raise
    finally:
        if tmp_dir.exists():
            shutil.rmtree(tmp_dir, ignore_errors=True)
    return net_path


def network_sources(sources_dir: Path) -> dict[str, Path]:
    """The source files by kind (suffix or ``netconvert.cfg``); a missing one is a UserError."""
    if not sources_dir.is_dir():
        raise UserError(str(sources_dir), "network.sources_dir",
                        "the network sources folder does not exist",
                        "point network.sources_dir at the folder with road.nod.xml and "
                        "road.edg.xml (the repository's sumo_net/)")
    found: dict[str, Path] = {}
    for path in sorted(sources_dir.iterdir()):
        if not path.is_file():
            continue
        if path.name == OPTIONS_FILE_NAME:
            found[OPTIONS_FILE_NAME] = path
            continue
        kind = next((s for s in SOURCE_KINDS if path.name.endswith(s)), None)
        if kind is None:
            continue
        if kind in found:
            raise UserError(str(sources_dir), "", f"more than one *{kind} file "
                            f"({found[kind].name}, {path.name})", "keep one file of each kind")
        found[kind] = path
    for kind in REQUIRED_KINDS:
        if kind not in found:
            raise UserError(str(sources_dir), "", f"no *{kind} file in the network sources folder",
                            f"add the {kind} file (see sumo_net/README.md)")
    return found


def netconvert_path() -> Path:
    """netconvert from the eclipse-sumo package, else ``$SUMO_HOME/bin``, else ``PATH``."""
    candidates: list[Path] = []
    try:
        import sumo  # the eclipse-sumo wheel

        candidates.append(Path(sumo.SUMO_HOME) / "bin" / "netconvert")
    except ImportError:
        pass
    if os.environ.get("SUMO_HOME"):
        candidates.append(Path(os.environ["SUMO_HOME"]) / "bin" / "netconvert")
    for candidate in candidates:
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    on_path = shutil.which("netconvert")
    if on_path:
        return Path(on_path)
    raise UserError("netconvert", "", "SUMO's netconvert was not found",
                    "install SUMO into the environment: pip install eclipse-sumo "
                    "(or set SUMO_HOME to a SUMO installation)")


@functools.lru_cache(maxsize=4)
def _netconvert_version(path: str) -> str:
    try:
        result = subprocess.run([path, "--version"], capture_output=True, text=True,
                                timeout=NETCONVERT_TIMEOUT_S, check=False)
    except OSError as exc:
        raise UserError(path, "", f"netconvert cannot be run ({exc})",
                        "reinstall SUMO: pip install --force-reinstall eclipse-sumo") from None
    first = (result.stdout or result.stderr).strip().splitlines()
    return first[0] if first else "unknown"


def netconvert_version() -> str:
    """netconvert's version line, e.g. ``Eclipse SUMO netconvert 1.28.0``."""
    return _netconvert_version(str(netconvert_path()))


def _cache_key(sources: dict[str, Path], version: str) -> str:
    digest = hashlib.sha256(version.encode())
    for kind in sorted(sources):
        digest.update(f"\0{kind}\0{sources[kind].name}\0".encode())
        digest.update(sources[kind].read_bytes())
    return digest.hexdigest()[:16]


def _run_netconvert(netconvert: Path, sources: dict[str, Path], out: Path,
                    sources_dir: Path) -> None:
    cmd = [str(netconvert)]
    if OPTIONS_FILE_NAME in sources:
        cmd += ["--configuration-file", str(sources[OPTIONS_FILE_NAME].resolve())]
    for kind, option in SOURCE_KINDS.items():
        if kind in sources:
            cmd += [option, str(sources[kind].resolve())]
    cmd += ["--output-file", str(out.resolve())]
    try:
        result = subprocess.run(cmd, capture_output=True, text=True,
                                timeout=NETCONVERT_TIMEOUT_S, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise UserError(str(sources_dir), "", f"netconvert could not run ({exc})",
                        "check the SUMO installation (pip install eclipse-sumo)") from None
    write_text_atomic(out.parent / "netconvert.log",
                      f"$ {' '.join(cmd)}\n{result.stdout}{result.stderr}")
    if result.returncode != 0 or not out.is_file():
        raise NetworkBuildError(
            str(sources_dir), "", f"netconvert failed: {_first_error(result)}",
            "fix the network sources (run netconvert on them by hand for the full log)")


def _first_error(result: subprocess.CompletedProcess[str]) -> str:
    lines = [ln.strip() for ln in (result.stderr + "\n" + result.stdout).splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("Error")]
    if errors:
        return errors[0]
    return lines[0] if lines else f"exit status {result.returncode}"
