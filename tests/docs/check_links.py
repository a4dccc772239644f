#!/usr/bin/env python3
"""Checks that every path the documentation names exists.

Usage: check_links.py REPO_ROOT

* Markdown links and images, `[text](path)`, in README.md and docs/*.md,
  relative to the page (web addresses and #anchors are not checked).
* Paths of source files, scripts and docs named in those pages
  (`common/...`, `coordinator/...`, `worker/...`, `tests/...`, `deploy/...`,
  `proto/...`, `docs/...`), relative to the repository root; `images/...`
  relative to docs/.
* `docs/...` paths named in any tracked file (code comments point there).
Prints one line per missing path ("FILE:LINE: PATH does not exist") and
exits 1 if there is any.
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
LINK = re.compile(r"\]\(([^)\s]+)\)")
TOP = r"(?:common|coordinator|worker|tests|deploy|proto|docs)"
SOURCE = re.compile(r"(?<![\w./-])(" + TOP + r"/[\w./*@{},-]*[\w*}])")
IMAGE = re.compile(r"(?<![\w./-])(images/[\w./-]*\w)")
DOCS = re.compile(r"(?<![\w./-])(docs/[\w./-]*\.(?:md|png|csv|json))")
missing = {}


def check(origin, line, base, target):
    if any(c in target for c in "*{}$<>") or target.startswith(("http://", "https://", "mailto:")):
        return
    target = target.split("#", 1)[0].rstrip(".,;:")
    if not target:
        return
    if not (base / target).exists():
        missing.setdefault(f"{origin}:{line}: {target} does not exist")


pages = [root / "README.md"] + sorted((root / "docs").glob("*.md"))
for page in pages:
    rel = page.relative_to(root)
    for number, text in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        for target in LINK.findall(text):
            check(rel, number, page.parent, target)
        if "kubectl" not in text:  # deploy/NAME there is a Kubernetes resource
            for target in SOURCE.findall(text):
                check(rel, number, root, target)
        for target in IMAGE.findall(text):
            check(rel, number, root / "docs", target)

tracked = subprocess.run(["git", "-C", str(root), "ls-files"], capture_output=True, text=True)
for name in tracked.stdout.splitlines() if tracked.returncode == 0 else []:
    path = root / name
    if path.suffix not in {".h", ".cpp", ".sh", ".py", ".txt", ".capnp", ".yaml", ".service", ".env", ""} or not path.is_file():
        continue
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (UnicodeDecodeError, OSError):
        continue
    for number, text in enumerate(lines, 1):
        for target in DOCS.findall(text):
            check(name, number, root, target)

for line in missing:
    print(line)
sys.exit(1 if missing else 0)
