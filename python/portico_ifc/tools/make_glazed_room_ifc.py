"""Writes an IFC4 room with one glazed window, on a located site.

    python -m portico_ifc.tools.make_glazed_room_ifc OUT.ifc [--transparency 0.9] [--true-north X,Y]

One room (an IfcSpace box, 4 m x 5 m x 3 m) closed by four walls, a floor
slab and a roof slab; its only opening is a window (1.2 m x 1.2 m, sill at
0.9 m) in the south wall (-y): an IfcWindow filling an IfcOpeningElement,
made of a frame (four 6 cm bars, styled opaque white) and a 12 mm glass
pane (styled 'Glass', IfcSurfaceStyleRendering with the given
Transparency, a blue-green colour), both in the middle of the wall's depth.
The site lies at 49 deg 6' 1.566" N, 8 deg 26' 11.5404" E (FZK-Haus's), and
the Model context's TrueNorth is the given direction in the plan.

The test ifc.glazing (tests/scene_io/ifc_glazing_test.sh) converts and
renders it (docs/importing-buildings.md, "Windows and glass").
"""

import argparse

import numpy as np
import ifcopenshell.api.aggregate as aggregate

from .make_office_ifc import Office

WIDTH, DEPTH, HEIGHT = 4.0, 5.0, 3.0     # the room, wall face to wall face
WALL, SLAB = 0.2, 0.3
WINDOW = (1.2, 1.2, 0.9)                 # width, height, sill
FRAME = 0.06                             # frame bars' width, and depth across the wall
GLASS = 0.012                            # pane thickness
LATITUDE = (49, 6, 1, 566000)
LONGITUDE = (8, 26, 11, 540400)


def _style(f, name, colour, transparency):
    rgb = f.createIfcColourRgb(None, *colour)
    rendering = f.createIfcSurfaceStyleRendering(rgb, transparency, None, None, None, None, None, None, "NOTDEFINED")
    return f.createIfcSurfaceStyle(name, "BOTH", [rendering])


def _window(office, transparency):
    """make_filling for Office._hole: a frame and a glass pane in the hole's middle."""
    f = office.f
    frame_style = _style(f, "Window frame", (0.9, 0.9, 0.9), 0.0)
    glass_style = _style(f, "Glass", (0.0, 0.5, 0.75), transparency)

    def make(name, lo, hi, storey):
        lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
        y = (lo[1] + hi[1]) / 2
        x0, x1, z0, z1 = lo[0], hi[0], lo[2], hi[2]
        bars = [((x0, x0 + FRAME), (z0, z1)), ((x1 - FRAME, x1), (z0, z1)),
                ((x0 + FRAME, x1 - FRAME), (z0, z0 + FRAME)), ((x0 + FRAME, x1 - FRAME), (z1 - FRAME, z1))]
        origin = (x0, y - FRAME / 2, z0)
        frame = [office.solid((bx[0], y - FRAME / 2, bz[0]), (bx[1], y + FRAME / 2, bz[1]), origin) for bx, bz in bars]
        glass = office.solid((x0 + FRAME, y - GLASS / 2, z0 + FRAME), (x1 - FRAME, y + GLASS / 2, z1 - FRAME), origin)
        for item in frame:
            f.createIfcStyledItem(item, [frame_style], None)
        f.createIfcStyledItem(glass, [glass_style], None)
        return office._box("IfcWindow", name, origin, None, storey, solids=frame + [glass])

    return make


def build(out, transparency, true_north):
    office = Office(1, 1)
    f = office.f
    site = f.by_type("IfcSite")[0]
    site.RefLatitude, site.RefLongitude = LATITUDE, LONGITUDE
    for context in f.by_type("IfcGeometricRepresentationContext"):
        if not context.is_a("IfcGeometricRepresentationSubContext"):
            context.TrueNorth = f.createIfcDirection(true_north)
    storey = office._entity("IfcBuildingStorey", "Ground floor")
    aggregate.assign_object(f, products=[storey], relating_object=office.building)
    h = WALL / 2
    x0, y0, x1, y1 = -h, -h, WIDTH + h, DEPTH + h       # wall centre lines at 0 and WIDTH, 0 and DEPTH
    box = office._box
    south = box("IfcWall", "South wall", (x0 - h, y0 - h, 0.0), (x1 + h, y0 + h, HEIGHT), storey)
    box("IfcWall", "North wall", (x0 - h, y1 - h, 0.0), (x1 + h, y1 + h, HEIGHT), storey)
    box("IfcWall", "West wall", (x0 - h, y0 + h, 0.0), (x0 + h, y1 - h, HEIGHT), storey)
    box("IfcWall", "East wall", (x1 - h, y0 + h, 0.0), (x1 + h, y1 - h, HEIGHT), storey)
    box("IfcSlab", "Floor", (x0 - h, y0 - h, -SLAB), (x1 + h, y1 + h, 0.0), storey)
    box("IfcSlab", "Roof", (x0 - h, y0 - h, HEIGHT), (x1 + h, y1 + h, HEIGHT + SLAB), storey)
    space = box("IfcSpace", "Room", (x0 + h, y0 + h, 0.0), (x1 - h, y1 - h, HEIGHT), None)
    aggregate.assign_object(f, products=[space], relating_object=storey)
    centre = (x0 + x1) / 2
    width, height, sill = WINDOW
    office._hole(south, "IfcWindow", "Window", (centre - width / 2, y0 - h - 0.05, sill),
                 (centre + width / 2, y0 + h + 0.05, sill + height), storey, _window(office, transparency))
    f.write(out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out")
    parser.add_argument("--transparency", type=float, default=0.9, help="the glass style's Transparency (0 opaque, 1 clear)")
    parser.add_argument("--true-north", default="0,1", help="X,Y: geographic north in the plan (default +y)")
    args = parser.parse_args(argv)
    north = tuple(float(x) for x in args.true_north.split(","))
    build(args.out, args.transparency, north)
    print(f"{args.out}: one room with a glazed window (Transparency {args.transparency}), true north {north}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
