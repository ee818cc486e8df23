#!/usr/bin/env python3
"""Fails when a source file is too long to read as one piece: a Rust file
with more than 700 lines of code before its tests (`#[cfg(test)] mod`), or
a page module (web/*.js) over 400 lines. Blank and comment-only lines do
not count.

    python3 scripts/file_sizes.py
"""
import os
import re
import sys

RUST_LIMIT = 700
JS_LIMIT = 400
TEST_TAIL = re.compile(r"^#\[cfg\(test\)\]\s*$", re.M)
SKIP = {"target", "node_modules", ".git", "pkg"}


def code_lines(text, comment):
    return sum(1 for ln in text.splitlines() if ln.strip() and not ln.strip().startswith(comment))


def main(root):
    bad = []
    for d, dirs, files in os.walk(root):
        dirs[:] = [x for x in dirs if x not in SKIP]
        for f in files:
            p = os.path.join(d, f)
            rel = os.path.relpath(p, root)
            if f.endswith(".rs"):
                text = open(p, encoding="utf-8").read()
                m = TEST_TAIL.search(text)
                n = code_lines(text[: m.start()] if m else text, "//")
                if n > RUST_LIMIT:
                    bad.append(f"{rel}: {n} lines of code before its tests (limit {RUST_LIMIT})")
            elif f.endswith(".js") and rel.startswith("web" + os.sep):
                n = code_lines(open(p, encoding="utf-8").read(), "//")
                if n > JS_LIMIT:
                    bad.append(f"{rel}: {n} lines of code (limit {JS_LIMIT})")
    for b in bad:
        print(b)
    if not bad:
        print("every source file within its size limit")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
