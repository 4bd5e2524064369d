#!/usr/bin/env python3
"""Check the built documentation site (what `make docs-check` runs after `make docs`).

    tools/docs_check.py [SITE]          SITE: the built site, default build/docs

1. Every internal link of every page resolves: the file exists and, for a link with a
   fragment, the target page has an element with that id.
2. Every image a page shows exists and is not empty.
3. A headless browser (Debian's chromium) renders the index and a demo page: their DOM holds
   the expected title and headings, and a screenshot of the demo page is not blank.

Exits 1 on any failure, naming each; prints one line per check otherwise.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

ROOT = Path(__file__).resolve().parents[1]
# the pages the browser renders, and text each must show once rendered
RENDERED = {
    "index.html": ["tapecoil", "User guide", "Theory manual", "Validation report", "API reference"],
    # MathJax_CHTML: the equations typeset, offline (the site carries its MathJax)
    "_generated/demos/tape_fold.html": [
        "Folding a tape spring through the snap",
        "tape_fold",
        "MathJax_CHTML",
    ],
}
BROWSERS = ("chromium", "chromium-browser", "google-chrome")


class Page(HTMLParser):
    """The ids, links and images of one HTML page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.images: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if attrs.get("id"):
            self.ids.add(attrs["id"])
        if tag == "a" and attrs.get("name"):
            self.ids.add(attrs["name"])
        if tag == "a" and attrs.get("href"):
            self.links.append(attrs["href"])
        if tag == "img" and attrs.get("src"):
            self.images.append(attrs["src"])


def parse(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text(errors="replace"))
    return page


def is_external(url: str) -> bool:
    parts = urlsplit(url)
    return bool(parts.scheme or parts.netloc) or url.startswith(("mailto:", "javascript:"))


def check_links(site: Path) -> tuple[int, list[str]]:
    """Every internal link and image of every page; returns (links checked, failures)."""
    pages = sorted(site.rglob("*.html"))
    parsed = {path: parse(path) for path in pages}
    failures, checked = [], 0
    for path, page in parsed.items():
        where = path.relative_to(site)
        for url in page.links:
            if is_external(url):
                continue
            checked += 1
            parts = urlsplit(url)
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                failures.append(f"{where}: link to {url}: no such file")
                continue
            fragment = unquote(parts.fragment)
            if fragment and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else parse(target).ids
                if fragment not in ids:
                    failures.append(f"{where}: link to {url}: no element with id '{fragment}'")
        for src in page.images:
            if is_external(src) or src.startswith("data:"):
                if not src.startswith("data:"):
                    failures.append(f"{where}: image {src} is not part of the site")
                continue
            checked += 1
            target = (path.parent / unquote(urlsplit(src).path)).resolve()
            if not target.is_file() or target.stat().st_size == 0:
                failures.append(f"{where}: image {src}: missing or empty")
    return checked, failures


def browser() -> str | None:
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    return None


def run_browser(exe: str, profile: str, *args: str) -> subprocess.CompletedProcess:
    flags = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--disable-dev-shm-usage",
        f"--user-data-dir={profile}",
    ]
    return subprocess.run([exe, *flags, *args], capture_output=True, text=True, timeout=120)


def blank(png: Path) -> str | None:
    """Why a screenshot is blank (None if it shows a page): too few colours, or too little
    that is not the background."""
    import numpy as np
    from matplotlib.image import imread

    pixels = imread(png)[..., :3]
    flat = (pixels.reshape(-1, 3) * 255).round().astype(int)
    colours = len(np.unique(flat[:: max(1, len(flat) // 200000)], axis=0))
    background = np.median(flat, axis=0)
    drawn = float(np.mean(np.abs(flat - background).sum(axis=1) > 30))
    if colours < 20 or drawn < 0.01:
        return f"{colours} colours, {100 * drawn:.2f} % of the pixels off the background"
    return None


def check_rendering(site: Path, shots: Path) -> list[str]:
    exe = browser()
    if exe is None:
        return ["no headless browser (chromium) found: install Debian's chromium (tools/env.sh does)"]
    failures = []
    with tempfile.TemporaryDirectory() as profile:
        for page, expected in RENDERED.items():
            url = (site / page).resolve().as_uri()
            # virtual time lets the page's scripts (MathJax) finish before the DOM is read
            done = run_browser(exe, profile, "--virtual-time-budget=10000", "--dump-dom", url)
            dom = done.stdout
            if done.returncode != 0 or "<html" not in dom:
                failures.append(
                    f"{page}: chromium --dump-dom failed (exit {done.returncode}): {done.stderr[-500:]}"
                )
                continue
            failures += [
                f"{page}: the rendered page does not show '{text}'" for text in expected if text not in dom
            ]
            png = shots / (Path(page).stem + ".png")
            shot = (f"--screenshot={png}", "--window-size=1280,1000")
            done = run_browser(exe, profile, "--virtual-time-budget=10000", *shot, url)
            if not png.exists():
                failures.append(f"{page}: no screenshot (exit {done.returncode}): {done.stderr[-500:]}")
                continue
            why = blank(png)
            if why:
                failures.append(f"{page}: the screenshot {png} is blank: {why}")
    return failures


def main(argv: list[str]) -> int:
    site = Path(argv[0]) if argv else ROOT / "build" / "docs"
    if not (site / "index.html").exists():
        print(f"docs check: {site}/index.html does not exist: build the site first (make docs)")
        return 1
    checked, failures = check_links(site)
    print(f"docs check: {checked} internal links and images of {len(list(site.rglob('*.html')))} pages")
    shots = site.parent / "docs-screenshots"
    shots.mkdir(parents=True, exist_ok=True)
    rendering = check_rendering(site, shots)
    if not rendering:
        print(f"docs check: chromium rendered {', '.join(RENDERED)} (screenshots in {shots})")
    failures += rendering
    for failure in failures:
        print(f"docs check: FAILED: {failure}")
    if failures:
        return 1
    print("docs check: passed")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main(sys.argv[1:]))
