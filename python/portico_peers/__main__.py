import argparse
import os
import sys

from portico_peers.store_view import UnsupportedView, read_view, write_view


def counts_of(text):
    try:
        counts = [int(s) for s in text.split(",")]
    except ValueError:
        sys.exit(f"--spp {text}: not a comma-separated list of sample counts")
    if not counts or min(counts) < 1:
        sys.exit(f"--spp {text}: sample counts must be at least 1")
    return counts


def main():
    ap = argparse.ArgumentParser(prog="python -m portico_peers", description=__import__("portico_peers").__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    v = sub.add_parser("view", help="write a store's camera view for the peers")
    v.add_argument("store")
    v.add_argument("out_dir")
    v.add_argument("--camera", help="camera name (default: the store's first)")
    v.add_argument("--portico", default="portico", help="the portico program")
    v.add_argument("--width", type=int)
    v.add_argument("--height", type=int)
    for name in ("mitsuba", "luxcore"):
        r = sub.add_parser(name, help=f"render a view with {name}")
        r.add_argument("view_dir")
        r.add_argument("--spp", default="16,64,256")
        r.add_argument("--threads", type=int, default=2)
        if name == "mitsuba":
            r.add_argument("--variant", default="llvm_ad_rgb")
        else:
            r.add_argument("--photongi", type=int, default=0, metavar="PHOTONS",
                           help="PhotonGI indirect cache from at most this many photons (0: plain path tracing)")
    a = ap.parse_args()
    try:
        if a.command == "view":
            view = write_view(a.portico, a.store, a.camera, a.out_dir, a.width, a.height)
            cam = view["camera"]
            print(f"{a.out_dir}: camera {cam['name']} {cam['width']}x{cam['height']}, "
                  f"{sum(m['triangles'] for m in view['materials'])} triangles in {len(view['materials'])} materials")
            return 0
        view = read_view(a.view_dir)
        counts = counts_of(a.spp)
        if a.command == "mitsuba":
            from portico_peers import mitsuba_view
            mitsuba_view.render(a.view_dir, view, counts, a.threads, a.variant, out=lambda s: print(s, flush=True))
            return 0
        from portico_peers import luxcore_view
        luxcore_view.render(a.view_dir, view, counts, a.threads, a.photongi, out=lambda s: print(s, flush=True))
        sys.stdout.flush()
        os._exit(0)   # pyluxcore crashes at interpreter exit
    except (OSError, ValueError, UnsupportedView) as e:
        sys.exit(f"portico_peers {a.command}: {e}")


if __name__ == "__main__":
    sys.exit(main())
