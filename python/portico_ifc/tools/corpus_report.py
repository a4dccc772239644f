"""The IFC corpus table of docs/ifc-corpus.md.

    PYTHONPATH=python .venv/bin/python3 -m portico_ifc.tools.corpus_report --bin build/bin \\
        tests/scenes/ifc/*.ifc tests/scenes/ifc/corpus/*.ifc [fetched/*.ifc] > corpus.md

For each model: converts it (python -m portico_ifc, outdoors open), stores it
(portico scene import building.json), checks watertightness
(portico_ifc.watertight: rays from inside every space), and traces a short
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
        converted = _run([sys.executable, "-m", "portico_ifc", model, out], timeout)
    except subprocess.TimeoutExpired:
        row["error"] = f"conversion took over {timeout} s"
        return row
    if converted.returncode != 0:
        row["error"] = _last_line(converted.stderr).replace(model, name)
        return row
    summary = json.loads(_last_line(converted.stdout))
    stored = _run([os.path.join(bin_dir, "portico"), "scene", "import", os.path.join(out, "building.json"), store],
                  timeout)
    row["import_s"] = round(time.time() - started, 1)
    if stored.returncode != 0:
        row["error"] = _last_line(stored.stderr)
        return row
    row.update({k: summary.get(k) for k in ("schema", "spaces", "cells", "portals", "doors", "doors_with_portal",
                                          "windows", "windows_with_portal", "openings_without_filling",
                                          "spaces_closed", "closing_m2", "lights", "cameras")})
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


def markdown(rows, threshold):
    out = ["| model | MB | schema | spaces | cells | portals | doors (portal) | windows (portal) | unfilled openings "
           "| spaces closed (m²) | lamps | cameras | import s | rays leaking | photons escaping | watertight |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            # The converter's line without the file name, up to its first clause.
            reason = r["error"].split(": ", 1)[-1].split(";")[0]
            out.append(f"| `{r['model']}` | {r['size_mb']} | not imported: {reason} |" + " |" * 12 + " no |")
            continue
        w = r["watertight"]
        tight = w["leak_share"] is not None and w["leak_share"] < threshold
        closed = f"{r['spaces_closed']} ({r['closing_m2']})" if r.get("spaces_closed") is not None else ""
        out.append(f"| `{r['model']}` | {r['size_mb']} | {r['schema']} | {r['spaces']} | {r['cells']} | {r['portals']} "
                   f"| {r['doors']} ({r['doors_with_portal']}) | {r['windows']} ({r['windows_with_portal']}) "
                   f"| {_cell(r['openings_without_filling'])} | {closed} | {r['lights']} | {r['cameras']} "
                   f"| {r['import_s']} | {w['leaks']}/{w['rays']} ({100 * w['leak_share']:.2f} %) "
                   f"| {_cell(r['photons_escaped'])} | {'yes' if tight else 'no: ' + ', '.join(w['leakiest'][:2])} |")
    imported = [r for r in rows if "error" not in r]
    tight = [r for r in imported if r["watertight"]["leak_share"] < threshold]
    out.append("")
    out.append(f"{len(rows)} models: {len(imported)} imported, {len(tight)} watertight "
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
