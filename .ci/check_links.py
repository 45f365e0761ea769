#!/usr/bin/env python3
"""Check the internal links of a built mdBook (Python 3 standard library only).

Usage: python3 .ci/check_links.py docs/book [--skip-dir rustdoc ...]

Walks every HTML file under the book folder, and for every relative `href` or `src`:
- the target file must exist (a link to a folder must have an index.html);
- a `#fragment` must name an `id` (or an `<a name>`) in the target page.
Absolute URLs (http, https, mailto, data, javascript, ...) and protocol-relative ones are
ignored. Pages under a skipped folder (default: `rustdoc`, the copied `cargo doc` output) are
not walked, but links INTO them are checked.

It also checks that no equation was mangled by Markdown: inside a MathJax span (`\\( ... \\)`
or `\\[ ... \\]` in the source, `\\( ... \\)` and `\\[ ... \\]` in the HTML), an `<em>` or `<strong>`
tag means an `_` or `*` was taken for emphasis.

Exit status 0 when everything resolves, 1 with the list of broken links otherwise, 2 on
usage errors.
"""

from __future__ import annotations

import os
import re
import sys
from html.parser import HTMLParser
from urllib.parse import unquote, urlsplit

LINK_ATTRS = {"href", "src"}


class PageParser(HTMLParser):
    """Collects the ids (anchors) and the links of one page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[tuple[int, str, str]] = []  # (line, attribute, value)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if name == "id" or (tag == "a" and name == "name"):
                self.ids.add(value)
            elif name in LINK_ATTRS:
                self.links.append((self.getpos()[0], name, value))

    handle_startendtag = handle_starttag


def is_external(url: str) -> bool:
    parts = urlsplit(url)
    return bool(parts.scheme) or url.startswith("//")


MATH = re.compile(r"\\\((.*?)\\\)|\\\[(.*?)\\\]", re.S)
CODE = re.compile(r"<(pre|code)\b.*?</\1>", re.S)


def mangled_math(text: str) -> list[str]:
    """Equations in which Markdown inserted emphasis tags."""
    text = CODE.sub("", text)
    bad = []
    for m in MATH.finditer(text):
        body = m.group(1) if m.group(1) is not None else m.group(2)
        if re.search(r"</?(em|strong)>", body):
            bad.append(re.sub(r"\s+", " ", body.strip())[:80])
    return bad


def main(argv: list[str]) -> int:
    args = list(argv[1:])
    skip = {"rustdoc"}
    root = None
    while args:
        a = args.pop(0)
        if a == "--skip-dir" and args:
            skip.add(args.pop(0).strip("/"))
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        elif root is None:
            root = a
        else:
            print(f"check_links: unexpected argument {a!r}", file=sys.stderr)
            return 2
    if root is None or not os.path.isdir(root):
        print("usage: check_links.py BOOK_DIR [--skip-dir DIR ...]", file=sys.stderr)
        return 2
    root = os.path.abspath(root)

    pages: dict[str, PageParser] = {}
    math_errors: list[str] = []

    def parse(path: str) -> PageParser:
        if path not in pages:
            p = PageParser()
            with open(path, encoding="utf-8", errors="replace") as f:
                text = f.read()
            p.feed(text)
            pages[path] = p
            rel = os.path.relpath(path, root)
            if not rel.split(os.sep)[0] in skip:
                for eq in mangled_math(text):
                    math_errors.append(f"{rel}: equation mangled by Markdown emphasis: {eq}")
        return pages[path]

    walked = []
    for dirpath, dirnames, filenames in os.walk(root):
        rel = os.path.relpath(dirpath, root)
        if rel != "." and rel.split(os.sep)[0] in skip:
            dirnames[:] = []
            continue
        for name in sorted(filenames):
            if name.endswith(".html"):
                walked.append(os.path.join(dirpath, name))

    broken: list[str] = []
    checked = 0
    for page in sorted(walked):
        parser = parse(page)
        rel_page = os.path.relpath(page, root)
        for line, attr, url in parser.links:
            url = url.strip()
            if not url or is_external(url):
                continue
            checked += 1
            parts = urlsplit(url)
            path, fragment = unquote(parts.path), unquote(parts.fragment)
            if path:
                if path.startswith("/"):
                    target = os.path.join(root, path.lstrip("/"))
                else:
                    target = os.path.normpath(os.path.join(os.path.dirname(page), path))
                if os.path.isdir(target):
                    target = os.path.join(target, "index.html")
            else:
                target = page
            where = f"{rel_page}:{line}: {attr}=\"{url}\""
            if not os.path.isfile(target):
                broken.append(f"{where}: no such file {os.path.relpath(target, root)}")
                continue
            if fragment and target.endswith(".html"):
                if fragment not in parse(target).ids:
                    broken.append(f"{where}: no id \"{fragment}\" in {os.path.relpath(target, root)}")

    problems = broken + math_errors
    if problems:
        print(f"check_links: {len(problems)} problem(s) in {root}:")
        for b in problems:
            print(f"  {b}")
        return 1
    print(f"check_links: {checked} internal links in {len(walked)} pages: all resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
