"""Load a report page in headless Chromium and check that every image decodes and every link
resolves (tests only).

The page itself has no JavaScript; the check runs on a copy with one script added that
records, after the load event, each image's source and whether it decoded, and the target
of each link as the browser resolves it.
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from urllib.parse import unquote, urlparse

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
         "--disable-background-networking", "--disable-extensions", "--no-first-run",
         "--virtual-time-budget=10000")
CHECK = ("<script>addEventListener('load',()=>{document.body.setAttribute('data-decoded',"
         "JSON.stringify([...document.images].map(i=>[i.getAttribute('src'),"
         "i.complete&&i.naturalWidth>0])));document.body.setAttribute('data-links',"
         "JSON.stringify([...document.links].map(a=>[a.getAttribute('href'),a.href])));"
         "});</script></body>")


def chromium() -> str | None:
    """Path of a Chromium executable, or ``None``; with ``TRACKFUSE_REQUIRE_BROWSER`` set
    (``.ci/run`` sets it) a missing browser is an error rather than a reason to skip."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if found := shutil.which(name):
            return found
    if os.environ.get("TRACKFUSE_REQUIRE_BROWSER"):
        raise RuntimeError("TRACKFUSE_REQUIRE_BROWSER is set but no chromium is installed")
    return None


def _loaded(page: Path) -> str:
    """The DOM of ``page`` after its load event, with the probe's records on its body."""
    browser = chromium()
    assert browser is not None
    probe = page.with_name(f".probe-{page.name}")
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", CHECK),
                     encoding="utf-8")
    try:
        return subprocess.run([browser, *FLAGS, "--dump-dom", probe.resolve().as_uri()],
                              capture_output=True, text=True, timeout=120, check=True).stdout
    finally:
        probe.unlink()


def _record(dom: str, name: str) -> list:
    found = re.search(rf'data-{name}="([^"]*)"', dom)
    assert found, "the page never finished loading"
    return json.loads(html.unescape(found.group(1)))


def decoded_images(page: Path, screenshot: Path) -> list[tuple[str, bool]]:
    """``[(src, decoded), ...]`` for every ``<img>`` of ``page``; writes a PNG screenshot."""
    dom = _loaded(page)
    subprocess.run([chromium(), *FLAGS, f"--screenshot={screenshot}", "--window-size=1280,2000",
                    page.resolve().as_uri()], capture_output=True, timeout=120, check=True)
    return [tuple(x) for x in _record(dom, "decoded")]


def _has_id(page: Path, fragment: str) -> bool:
    """Whether ``page`` has an element whose ``id`` is ``fragment`` (any page when empty)."""
    return not fragment or bool(re.search(rf"""id=['"]?{re.escape(unquote(fragment))}['" >]""",
                                          page.read_text(encoding="utf-8", errors="replace")))


def broken_links(page: Path) -> tuple[int, list[str]]:
    """``(links, broken)``: how many links ``page`` has, and the ``href`` of each whose target
    the browser resolves to a missing file, or to a file without the ``id`` its fragment
    names (every link of a report is to a local file)."""
    links = _record(_loaded(page), "links")
    broken = []
    for href, resolved in links:
        url = urlparse(resolved)
        target = Path(unquote(url.path))
        if target.name == f".probe-{page.name}":  # a link within the page itself
            target = target.with_name(page.name)
        if not (url.scheme == "file" and target.is_file() and _has_id(target, url.fragment)):
            broken.append(href)
    return len(links), broken
