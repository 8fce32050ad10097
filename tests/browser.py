"""Load a report page in headless Chromium and check that every image decodes (tests only).

The page itself has no JavaScript; the check runs on a copy with one script added that
records, after the load event, each image's source and whether it decoded.
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
         "--disable-background-networking", "--disable-extensions", "--no-first-run",
         "--virtual-time-budget=10000")
CHECK = ("<script>addEventListener('load',()=>{document.body.setAttribute('data-decoded',"
         "JSON.stringify([...document.images].map(i=>[i.getAttribute('src'),"
         "i.complete&&i.naturalWidth>0])));});</script></body>")


def chromium() -> str | None:
    """Path of a Chromium executable, or ``None``; with ``TRACKFUSE_REQUIRE_BROWSER`` set
    (``.ci/run`` sets it) a missing browser is an error rather than a reason to skip."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if found := shutil.which(name):
            return found
    if os.environ.get("TRACKFUSE_REQUIRE_BROWSER"):
        raise RuntimeError("TRACKFUSE_REQUIRE_BROWSER is set but no chromium is installed")
    return None


def decoded_images(page: Path, screenshot: Path) -> list[tuple[str, bool]]:
    """``[(src, decoded), ...]`` for every ``<img>`` of ``page``; writes a PNG screenshot."""
    browser = chromium()
    assert browser is not None
    probe = page.with_name(f".probe-{page.name}")
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", CHECK),
                     encoding="utf-8")
    try:
        dom = subprocess.run([browser, *FLAGS, "--dump-dom", probe.resolve().as_uri()],
                             capture_output=True, text=True, timeout=120, check=True).stdout
    finally:
        probe.unlink()
    subprocess.run([browser, *FLAGS, f"--screenshot={screenshot}", "--window-size=1280,2000",
                    page.resolve().as_uri()], capture_output=True, timeout=120, check=True)
    found = re.search(r'data-decoded="([^"]*)"', dom)
    assert found, "the page never finished loading"
    return [tuple(x) for x in json.loads(html.unescape(found.group(1)))]
