"""The documentation site: `mkdocs build --strict` (what `make docs` runs) builds it without a
warning, so a broken link or a stale reference fails here, and headless Chromium opens it: the
home page leads to every part, the scenario fields page holds the schema's table and the
command line page every command, and no page logs an error or loads anything from the
network."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from sse_cosim.scenario.fields import fields_markdown

pytestmark = pytest.mark.browser
ROOT = Path(__file__).resolve().parents[2]
COMMANDS = ["batch", "bench", "falsify", "fields", "network", "report", "run", "safety", "sweep"]


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """The site as `make docs` builds it (``--strict``), in a folder of its own."""
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(out)], cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def site(built: Path) -> Iterator[str]:
    """The built site, served over HTTP on this machine as a reader's server would (its search
    index is loaded by a worker, which a page opened from a file may not start); the address
    of its root."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), partial(Quiet, directory=str(built)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    thread.join()


class Quiet(SimpleHTTPRequestHandler):
    """Serves the site without logging each request."""

    def log_message(self, *args: object) -> None:
        pass


@pytest.fixture()
def page(browser, site: str) -> Iterator:
    """A page, and what went wrong on it: errors logged, and requests off the site."""
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    page.on("request", lambda request: None if request.url.startswith((site, "data:"))
            else errors.append(f"loaded {request.url}"))
    yield page, errors
    page.close()


def test_the_home_page_leads_to_every_part(site: str, page) -> None:
    tab, errors = page
    tab.goto(site)
    assert "sse-cosim" in tab.title()
    text = tab.locator(".md-nav--primary").first.text_content()
    for part in ("Tutorial", "How-to guides", "Reference", "Explanation"):
        assert part in text
    tab.get_by_role("link", name="your first run").first.click()
    assert "make run" in tab.locator("article").inner_text()
    assert errors == []


def test_the_pages_open_from_the_file_system(built: Path, browser) -> None:
    """`make docs` then opening site/index.html, as the README says: its links lead to pages
    (files, not folders a browser would list)."""
    tab = browser.new_page()
    tab.goto((built / "index.html").as_uri())
    tab.get_by_role("link", name="your first run").first.click()
    assert tab.url.endswith("tutorial/first_run.html")
    assert "make run" in tab.locator("article").inner_text()
    tab.close()


def test_the_fields_page_holds_the_schemas_table(site: str, page) -> None:
    tab, errors = page
    tab.goto(site + "reference/fields.html")
    rows = tab.locator("article table tr")
    fields = [line for line in fields_markdown().splitlines() if line.startswith("| `")]
    assert rows.count() == len(fields) + 1  # and its header
    assert "automated.<vehicle id>.nominal_speed_mps" in tab.locator("article").inner_text()
    assert errors == []


def test_the_command_line_page_documents_every_command(site: str, page) -> None:
    tab, errors = page
    tab.goto(site + "reference/cli.html")
    text = tab.locator("article").inner_text()
    for command in COMMANDS:
        assert f"sse-cosim {command} [OPTIONS]" in text, command
    assert errors == []
