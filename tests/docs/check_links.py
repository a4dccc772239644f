#!/usr/bin/env python3
"""Checks that every path the documentation names exists.

Usage: check_links.py REPO_ROOT

* Markdown links and images, `[text](path)`, in README.md and docs/*.md,
  relative to the page (web addresses and #anchors are not checked).
* Paths of source files, scripts and docs named in those pages
  (`common/...`, `coordinator/...`, `worker/...`, `tests/...`, `deploy/...`,
  `proto/...`, `docs/...`, `python/...`), relative to the repository root; `images/...`
  relative to docs/.
* `docs/...` paths named in any tracked file (code comments point there).
* No page and no tracked source file names a path outside the repository,
  which a clone does not have: a `../` path climbing above the repository
  (from its page), an absolute path into a machine's working folders
  (/work/, /home/, /root/), or the `shared/` folder of tools some checkouts
  had beside them.
Prints one line per problem ("FILE:LINE: PATH does not exist", "FILE:LINE:
PATH is outside the repository") and exits 1 if there is any.
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
LINK = re.compile(r"\]\(([^)\s]+)\)")
TOP = r"(?:common|coordinator|worker|tests|deploy|proto|docs|python)"
SOURCE = re.compile(r"(?<![\w./-])(" + TOP + r"/[\w./*@{},-]*[\w*}])")
IMAGE = re.compile(r"(?<![\w./-])(images/[\w./-]*\w)")
DOCS = re.compile(r"(?<![\w./-])(docs/[\w./-]*\.(?:md|png|csv|json))")
# Paths outside the repository; a `../` path counts when it climbs above the root.
CLIMB = re.compile(r"(?<![\w./-])((?:\.\./)+[\w./-]*)")
ELSEWHERE = re.compile(r"(?<![\w./~-])((?:/(?:work|home|root)/|(?:\.\./)*shared/)[\w./-]*)")
missing = {}


def check(origin, line, base, target):
    if any(c in target for c in "*{}$<>") or target.startswith(("http://", "https://", "mailto:")):
        return
    target = target.split("#", 1)[0].rstrip(".,;:")
    if not target:
        return
    if not (base / target).exists():
        missing.setdefault(f"{origin}:{line}: {target} does not exist")


def check_inside(origin, line, base, text):
    for target in ELSEWHERE.findall(text):
        missing.setdefault(f"{origin}:{line}: {target} is outside the repository")
    for target in CLIMB.findall(text):
        if not (base / target).resolve().is_relative_to(root):
            missing.setdefault(f"{origin}:{line}: {target} is outside the repository")


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
        check_inside(rel, number, page.parent, text)

tracked = subprocess.run(["git", "-C", str(root), "ls-files"], capture_output=True, text=True)
for name in tracked.stdout.splitlines() if tracked.returncode == 0 else []:
    path = root / name
    if path == pathlib.Path(__file__).resolve() or (path.suffix == ".md" and path in pages):
        continue  # this file names what it looks for; pages were read above
    if path.suffix not in {".h", ".cpp", ".sh", ".py", ".txt", ".capnp", ".yaml", ".service", ".env", ".md", ""} or not path.is_file():
        continue
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (UnicodeDecodeError, OSError):
        continue
    for number, text in enumerate(lines, 1):
        if path.suffix != ".md":
            for target in DOCS.findall(text):
                check(name, number, root, target)
        # Source files' `../` paths are code (path traversal refused, relative
        # includes), not pointers for a reader: only pages climb.
        if path.suffix == ".md":
            check_inside(name, number, path.parent, text)
        else:
            for target in ELSEWHERE.findall(text):
                missing.setdefault(f"{name}:{number}: {target} is outside the repository")

for line in missing:
    print(line)
sys.exit(1 if missing else 0)
