"""Files the converter writes: OBJ meshes, and JSON's small values."""

import math
import re


def slug(text):
    return re.sub(r"[^A-Za-z0-9]+", "-", text).strip("-").lower()[:40] or "x"


def write_obj(path, triangles):
    with open(path, "w") as f:
        for t in triangles:
            for p in t:
                f.write(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
        for i in range(len(triangles)):
            f.write(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}\n")


def rounded(point):
    return [round(float(x), 4) for x in point]


def site_json(site):
    """IFC's true north (x, y) in the plan is portico's (x, 0, -y); its
    azimuth is measured from +Z towards +X, as --sun's."""
    x, y = site.true_north
    azimuth = math.degrees(math.atan2(x, -y)) % 360.0
    return {"latitude": site.latitude, "longitude": site.longitude, "north_azimuth": round(azimuth, 4) % 360.0}
