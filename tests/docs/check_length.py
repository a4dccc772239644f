#!/usr/bin/env python3
"""Checks that every documentation page stays short enough to read.

Usage: check_length.py REPO_ROOT [LIMIT]

A page (README.md, docs/*.md and every other tracked Markdown file) says
what it answers, how to run it, the current figures and their limits; run
logs belong in commit messages. Prints one line per page over LIMIT lines
(default 300), "FILE: N lines (at most LIMIT)", and exits 1 if there is any.
"""
import pathlib
import subprocess
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
limit = int(sys.argv[2]) if len(sys.argv) > 2 else 300

tracked = subprocess.run(["git", "-C", str(root), "ls-files", "*.md"], capture_output=True, text=True)
pages = {root / "README.md", *(root / "docs").glob("*.md")}
pages.update(root / name for name in tracked.stdout.splitlines() if tracked.returncode == 0)
long_pages = []
for page in sorted(p for p in pages if p.is_file()):
    lines = len(page.read_text(encoding="utf-8").splitlines())
    if lines > limit:
        long_pages.append(f"{page.relative_to(root)}: {lines} lines (at most {limit})")
for line in long_pages:
    print(line)
sys.exit(1 if long_pages else 0)
