#!/usr/bin/env python3
"""Check that the built book's equations render offline (Python 3 standard library only).

Usage: python3 .ci/check_math.py docs/book [--browser | --no-browser]

Static checks (always; cheap):
- no page (outside the copied `rustdoc/`) loads a script, stylesheet, image or font from
  the network (`src`/`href` on `<script>`, `<link>`, `<img>`, `<iframe>` with a scheme or `//`),
  and none mentions MathJax;
- the vendored KaTeX (`vendor/katex/`: katex.min.js, katex.min.css,
  contrib/auto-render.min.js, LICENSE) is in the book, and every `url(...)` that
  katex.min.css names exists;
- every page with an equation (`\\(` or `\\[` outside code) loads those three files;
- no TeX is written between dollars (`$\\...`), which neither the book nor KaTeX's
  auto-render (as configured in docs/theme/head.hbs) treats as an equation.

Browser check (with `--browser`, or by default when `chromium` or `chromium-browser` is on
the PATH; `--no-browser` skips it): every page with an equation is opened in headless
Chromium with host resolution disabled (so any network request fails), and the rendered
DOM must hold one KaTeX rendering per equation of the page, no `katex-error`, and no
delimiter left as text.

Exit status 0 when everything holds, 1 with the list of problems otherwise, 2 on usage
errors.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from html.parser import HTMLParser

KATEX = "vendor/katex"
ASSETS = ["katex.min.js", "katex.min.css", "contrib/auto-render.min.js", "LICENSE"]
CODE = re.compile(r"<(pre|code|script|style)\b.*?</\1>", re.S)
MATH = re.compile(r"\\\((.*?)\\\)|\\\[(.*?)\\\]", re.S)


class Refs(HTMLParser):
    """The resources a page loads: (tag, attribute, url)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.refs: list[tuple[str, str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag not in ("script", "link", "img", "iframe", "source", "audio", "video"):
            return
        for name, value in attrs:
            if name in ("src", "href") and value:
                self.refs.append((tag, value.strip()))

    handle_startendtag = handle_starttag


def equations(html: str) -> int:
    """Number of `\\( \\)` and `\\[ \\]` spans outside code, scripts and styles."""
    return len(MATH.findall(CODE.sub("", html)))


def pages(root: str) -> list[str]:
    out = []
    for dirpath, dirnames, filenames in os.walk(root):
        rel = os.path.relpath(dirpath, root)
        if rel != "." and rel.split(os.sep)[0] in ("rustdoc", "vendor"):
            dirnames[:] = []
            continue
        out += [os.path.join(dirpath, f) for f in filenames if f.endswith(".html")]
    return sorted(out)


def static_checks(root: str) -> tuple[list[str], list[tuple[str, int]]]:
    problems: list[str] = []
    with_math: list[tuple[str, int]] = []
    katex = os.path.join(root, KATEX)
    for asset in ASSETS:
        if not os.path.isfile(os.path.join(katex, asset)):
            problems.append(f"{KATEX}/{asset}: missing (docs/update_katex.sh vendors it)")
    css = os.path.join(katex, "katex.min.css")
    if os.path.isfile(css):
        with open(css, encoding="utf-8") as f:
            urls = re.findall(r"url\(([^)]*)\)", f.read())
        if not urls:
            problems.append(f"{KATEX}/katex.min.css: names no font")
        for url in urls:
            url = url.strip("'\"")
            if re.match(r"^[a-z]+:|^//", url):
                problems.append(f"{KATEX}/katex.min.css: loads {url} from the network")
            elif not os.path.isfile(os.path.join(katex, url)):
                problems.append(f"{KATEX}/katex.min.css: font {url} missing")
    for page in pages(root):
        rel = os.path.relpath(page, root)
        with open(page, encoding="utf-8", errors="replace") as f:
            html = f.read()
        parser = Refs()
        parser.feed(html)
        loaded = set()
        for tag, url in parser.refs:
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:|^//", url) and not url.startswith("data:"):
                problems.append(f"{rel}: <{tag}> loads {url} from the network")
            loaded.add(os.path.normpath(os.path.join(os.path.dirname(rel), url.split("?")[0])))
        if re.search(r"mathjax", CODE.sub("", html), re.I):
            problems.append(f"{rel}: mentions MathJax")
        for dollar in re.findall(r"\$\\[^$<]{0,40}", CODE.sub("", html)):
            problems.append(f"{rel}: TeX between dollars is not rendered (write \\\\( \\\\)): {dollar}")
        n = equations(html)
        if n:
            with_math.append((page, n))
            for asset in ASSETS[:3]:
                if os.path.normpath(f"{KATEX}/{asset}") not in loaded:
                    problems.append(f"{rel}: has {n} equation(s) but does not load {KATEX}/{asset}")
    return problems, with_math


def browser_checks(browser: str, with_math: list[tuple[str, int]], root: str) -> list[str]:
    problems = []
    with tempfile.TemporaryDirectory() as profile:
        for page, n in with_math:
            rel = os.path.relpath(page, root)
            cmd = [
                browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking", "--disable-component-update",
                "--disable-sync", f"--user-data-dir={profile}",
                # Any host name fails to resolve: the page must render from local files only.
                "--host-resolver-rules=MAP * ~NOTFOUND",
                "--virtual-time-budget=10000", "--dump-dom", "file://" + os.path.abspath(page),
            ]
            try:
                dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120).stdout
            except subprocess.TimeoutExpired:
                problems.append(f"{rel}: the browser timed out")
                continue
            rendered = len(re.findall(r'class="katex"', dom))
            errors = len(re.findall(r'class="katex-error"', dom))
            left = equations(re.sub(r'<span class="katex">.*?</annotation>', "", dom, flags=re.S))
            if rendered != n or errors or left:
                problems.append(
                    f"{rel}: {n} equation(s), {rendered} rendered by KaTeX, "
                    f"{errors} KaTeX error(s), {left} left as text"
                )
    return problems


def main(argv: list[str]) -> int:
    args = list(argv[1:])
    mode = "auto"
    root = None
    for a in args:
        if a == "--browser":
            mode = "on"
        elif a == "--no-browser":
            mode = "off"
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        elif root is None:
            root = a
        else:
            print(f"check_math: unexpected argument {a!r}", file=sys.stderr)
            return 2
    if root is None or not os.path.isdir(root):
        print("usage: check_math.py BOOK_DIR [--browser | --no-browser]", file=sys.stderr)
        return 2
    root = os.path.abspath(root)
    problems, with_math = static_checks(root)
    total = sum(n for _, n in with_math)
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if mode == "on" and not browser:
        print("check_math: --browser given but no chromium on the PATH", file=sys.stderr)
        return 2
    checked_in_browser = False
    if mode != "off" and browser and not problems:
        problems += browser_checks(browser, with_math, root)
        checked_in_browser = True
    if problems:
        print(f"check_math: {len(problems)} problem(s) in {root}:")
        for p in problems:
            print(f"  {p}")
        return 1
    how = "rendered offline in headless Chromium" if checked_in_browser else "static checks only (no chromium)"
    print(f"check_math: {total} equations in {len(with_math)} pages, KaTeX vendored, no network: {how}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
