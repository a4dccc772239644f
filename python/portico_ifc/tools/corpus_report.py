"""The IFC corpus table of docs/ifc-corpus.md.

    PYTHONPATH=python .venv/bin/python3 -m portico_ifc.tools.corpus_report --bin build/bin \\
        tests/scenes/ifc/*.ifc tests/scenes/ifc/corpus/*.ifc [fetched/*.ifc] > corpus.md

For each model: imports it (portico scene import --keep-conversion: the
converter, outdoors open, then the store; a model without usable IfcSpace
by rooms found in its geometry), checks watertightness
(portico_ifc.watertight: rays from inside every space or found room), and traces a short
photon pass (portico render --photons) for the share of photons that escape.
Prints a Markdown table, one row per model; a model that does not import
gets its one-line reason.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from .. import watertight


def _last_line(text):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    # "the IFC converter failed (...; its message is above)": the converter's own line says why.
    if len(lines) > 1 and lines[-1].endswith("its message is above)"):
        return lines[-2].strip()
    return lines[-1].strip() if lines else "no message"


def _run(arguments, timeout):
    return subprocess.run(arguments, capture_output=True, text=True, timeout=timeout)


def report(model, bin_dir, work, photons, rays_per_space, timeout):
    name = os.path.basename(model)
    row = {"model": name, "size_mb": round(os.path.getsize(model) / 1e6, 2)}
    out = os.path.join(work, "converted")
    store = os.path.join(work, "store")
    started = time.time()
    try:
        stored = _run([os.path.join(bin_dir, "portico"), "scene", "import", "--keep-conversion", out, model, store],
                      timeout)
    except subprocess.TimeoutExpired:
        row["error"] = f"import took over {timeout} s"
        return row
    row["import_s"] = round(time.time() - started, 1)
    if stored.returncode != 0:
        row["error"] = _last_line(stored.stderr).replace(model, name)
        return row
    conversion = json.load(open(os.path.join(out, "conversion.json")))
    summary = conversion["summary"]
    row.update({k: summary.get(k) for k in ("schema", "spaces", "cells", "portals", "doors", "doors_with_portal",
                                          "windows", "windows_with_portal", "openings_without_filling",
                                          "spaces_closed", "closing_m2", "lights", "cameras", "rooms_found")})
    row["cells_from"] = summary.get("cells_from", "spaces")
    row["watertight"] = watertight.check(out, rays_per_space)
    image = os.path.join(work, "pass.png")
    rendered = _run([os.path.join(bin_dir, "portico"), "render", store, "-o", image, "--photons", str(photons),
                     "--spp", "1", "--gather", "1", "--width", "16", "--height", "12", "--workers", "2"], timeout)
    if rendered.returncode == 0:
        p = json.load(open(image + ".json"))["photons"]
        row["photons_escaped"] = round(p["escaped"] / max(1, p["emitted"]), 4)
    else:
        row["photons_escaped"] = _last_line(rendered.stderr)
    return row


def _cell(value):
    return "" if value is None else str(value)


def _portal_count(found, total):
    return f"{total} ({found})" if found is not None else f"{total}"


def markdown(rows, threshold):
    out = ["| model | MB | schema | IfcSpaces | cells from: rooms | cells | portals | doors (portal) | windows (portal) "
           "| unfilled openings | spaces closed (m²) | lamps | cameras | import s | rays leaking | photons escaping "
           "| watertight |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            # The message without "portico: " and the file name, up to its first clause.
            reason = r["error"].split(": ", 2)[-1].split(";")[0] if r["error"].startswith("portico: ") else \
                r["error"].split(": ", 1)[-1].split(";")[0]
            out.append(f"| `{r['model']}` | {r['size_mb']} | not imported: {reason} |" + " |" * 13 + " no |")
            continue
        w = r["watertight"]
        tight = w["leak_share"] is not None and w["leak_share"] < threshold
        closed = f"{r['spaces_closed']} ({r['closing_m2']})" if r.get("spaces_closed") is not None else ""
        rooms = f"rooms found: {r['rooms_found']}" if r["cells_from"] == "rooms found" else f"spaces: {r['spaces']}"
        out.append(f"| `{r['model']}` | {r['size_mb']} | {r['schema']} | {r['spaces']} | {rooms} | {r['cells']} "
                   f"| {r['portals']} | {_portal_count(r['doors_with_portal'], r['doors'])} "
                   f"| {_portal_count(r['windows_with_portal'], r['windows'])} "
                   f"| {_cell(r['openings_without_filling'])} | {closed} | {r['lights']} | {r['cameras']} "
                   f"| {r['import_s']} | {w['leaks']}/{w['rays']} ({100 * w['leak_share']:.2f} %) "
                   f"| {_cell(r['photons_escaped'])} | {'yes' if tight else 'no: ' + ', '.join(w['leakiest'][:2])} |")
    imported = [r for r in rows if "error" not in r]
    tight = [r for r in imported if r["watertight"]["leak_share"] < threshold]
    found = [r for r in imported if r["cells_from"] == "rooms found"]
    out.append("")
    out.append(f"{len(rows)} models: {len(imported)} imported ({len(found)} by rooms found), {len(tight)} watertight "
               f"(under {100 * threshold:g} % of rays leaking).")
    return "\n".join(out)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="portico_ifc.tools.corpus_report", description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--bin", default="build/bin", help="directory of the portico binary")
    parser.add_argument("--photons", type=int, default=20000)
    parser.add_argument("--rays-per-space", type=int, default=64)
    parser.add_argument("--threshold", type=float, default=0.01, help="watertight: leak share below this")
    parser.add_argument("--timeout", type=int, default=900, help="seconds per step")
    parser.add_argument("--json", help="also write the rows as JSON here")
    args = parser.parse_args(argv)
    rows = []
    for model in args.models:
        with tempfile.TemporaryDirectory() as work:
            row = report(model, args.bin, work, args.photons, args.rays_per_space, args.timeout)
        print(json.dumps(row), file=sys.stderr)
        rows.append(row)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    print(markdown(rows, args.threshold))
    return 0


if __name__ == "__main__":
    sys.exit(main())
