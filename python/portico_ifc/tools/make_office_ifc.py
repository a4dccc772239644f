"""Writes an IFC4 office: storeys of rooms either side of a corridor.

    python -m portico_ifc.tools.make_office_ifc OUT.ifc [--storeys 2] [--rooms-per-side 25]

Every storey has a row of rooms each side of a central corridor; every room
is an IfcSpace (an extruded box) with a door (IfcDoor filling an
IfcOpeningElement that voids the corridor wall); every fifth room has an
IfcWindow in the facade; the corridor of the ground storey has an entrance
door in the west wall; a stair opening (an IfcOpeningElement voiding the
slab) at the corridor's east end joins each storey to the one above. Walls
are IfcWall boxes, floors and the roof IfcSlab boxes. Lengths in metres, Z up.

It stands in for a real large model (none is freely available) when
measuring `portico scene import` (docs/importing-buildings.md, "Costs").
"""

import argparse

import numpy as np
import ifcopenshell
import ifcopenshell.api.aggregate
import ifcopenshell.api.context
import ifcopenshell.api.feature
import ifcopenshell.api.geometry
import ifcopenshell.api.project
import ifcopenshell.api.root
import ifcopenshell.api.spatial
import ifcopenshell.api.unit

ROOM_WIDTH = 4.0        # along x, wall centre to wall centre
ROOM_DEPTH = 5.0        # along y, wall centre to wall centre
CORRIDOR = 2.0          # along y, wall centre to wall centre
WALL = 0.2              # wall thickness
SLAB = 0.3              # slab thickness
CLEAR_HEIGHT = 3.0      # floor to ceiling
DOOR = (0.9, 2.1)       # width, height
WINDOW = (1.2, 1.2, 0.9)  # width, height, sill
STAIR_LENGTH = 4.0      # along x, at the corridor's east end
WINDOW_EVERY = 5        # rooms per window


class Office:
    def __init__(self, storeys, rooms_per_side):
        self.f = ifcopenshell.api.project.create_file(version="IFC4")
        f = self.f
        self.project = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProject", name="Generated office")
        length = ifcopenshell.api.unit.add_si_unit(f, unit_type="LENGTHUNIT")
        ifcopenshell.api.unit.assign_unit(f, units=[length])
        model = ifcopenshell.api.context.add_context(f, context_type="Model")
        self.body = ifcopenshell.api.context.add_context(f, context_type="Model", context_identifier="Body",
                                                         target_view="MODEL_VIEW", parent=model)
        site = self._entity("IfcSite", "Site")
        self.building = self._entity("IfcBuilding", "Office")
        ifcopenshell.api.aggregate.assign_object(f, products=[site], relating_object=self.project)
        ifcopenshell.api.aggregate.assign_object(f, products=[self.building], relating_object=site)
        self.storeys, self.rooms_per_side = storeys, rooms_per_side
        self.length = rooms_per_side * ROOM_WIDTH
        self.depth = 2 * ROOM_DEPTH + CORRIDOR
        self.storey_height = CLEAR_HEIGHT + SLAB

    def _entity(self, ifc_class, name):
        product = ifcopenshell.api.root.create_entity(self.f, ifc_class=ifc_class, name=name)
        ifcopenshell.api.geometry.edit_object_placement(self.f, product=product)
        return product

    def solid(self, lo, hi, origin):
        """The box lo..hi (world coordinates) as a solid extruded up, in the
        coordinates of a product placed at `origin`."""
        f = self.f
        size = np.subtract(hi, lo)
        start = tuple(float(x) for x in np.subtract(lo, origin))
        profile = f.createIfcRectangleProfileDef(
            "AREA", None, f.createIfcAxis2Placement2D(f.createIfcCartesianPoint((size[0] / 2, size[1] / 2))),
            float(size[0]), float(size[1]))
        return f.createIfcExtrudedAreaSolid(profile, f.createIfcAxis2Placement3D(f.createIfcCartesianPoint(start)),
                                            f.createIfcDirection((0.0, 0.0, 1.0)), float(size[2]))

    def _box(self, ifc_class, name, lo, hi, container=None, solids=None):
        """A product placed at lo whose body is the box lo..hi (world
        coordinates), extruded up; or the given solids, in its coordinates."""
        f = self.f
        product = ifcopenshell.api.root.create_entity(f, ifc_class=ifc_class, name=name)
        representation = f.createIfcShapeRepresentation(self.body, "Body", "SweptSolid",
                                                         solids or [self.solid(lo, hi, lo)])
        ifcopenshell.api.geometry.assign_representation(f, product=product, representation=representation)
        matrix = np.eye(4)
        matrix[:3, 3] = lo
        ifcopenshell.api.geometry.edit_object_placement(f, product=product, matrix=matrix)
        if container is not None:
            ifcopenshell.api.spatial.assign_container(f, products=[product], relating_structure=container)
        return product

    def _hole(self, host, filling_class, name, lo, hi, storey, make_filling=None):
        """An opening lo..hi voiding `host`, filled by a door or window: a
        thin leaf in its middle, or make_filling(name, lo, hi, storey)."""
        opening = self._box("IfcOpeningElement", f"{name} opening", lo, hi)
        ifcopenshell.api.feature.add_feature(self.f, feature=opening, element=host)
        if make_filling is not None:
            filling = make_filling(name, lo, hi, storey)
        else:
            thin = int(np.argmin(np.subtract(hi, lo)))
            leaf_lo, leaf_hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
            middle = (leaf_lo[thin] + leaf_hi[thin]) / 2
            leaf_lo[thin], leaf_hi[thin] = middle - 0.025, middle + 0.025
            filling = self._box(filling_class, name, leaf_lo, leaf_hi, storey)
        ifcopenshell.api.feature.add_filling(self.f, opening=opening, element=filling)

    def storey(self, level):
        f = self.f
        z = level * self.storey_height
        storey = self._entity("IfcBuildingStorey", f"Level {level}")
        storey.Elevation = z
        ifcopenshell.api.aggregate.assign_object(f, products=[storey], relating_object=self.building)
        top = z + CLEAR_HEIGHT
        h, n, length, depth = WALL / 2, self.rooms_per_side, self.length, self.depth
        corridor_lo, corridor_hi = ROOM_DEPTH, ROOM_DEPTH + CORRIDOR
        walls = {
            "south": self._box("IfcWall", f"L{level} south wall", (-h, -h, z), (length + h, h, top), storey),
            "north": self._box("IfcWall", f"L{level} north wall", (-h, depth - h, z), (length + h, depth + h, top), storey),
            "west": self._box("IfcWall", f"L{level} west wall", (-h, h, z), (h, depth - h, top), storey),
            "east": self._box("IfcWall", f"L{level} east wall", (length - h, h, z), (length + h, depth - h, top), storey),
            "corridor south": self._box("IfcWall", f"L{level} corridor south wall",
                                        (h, corridor_lo - h, z), (length - h, corridor_lo + h, top), storey),
            "corridor north": self._box("IfcWall", f"L{level} corridor north wall",
                                        (h, corridor_hi - h, z), (length - h, corridor_hi + h, top), storey),
        }
        for i in range(1, n):
            x = i * ROOM_WIDTH
            for y0, y1 in ((h, corridor_lo - h), (corridor_hi + h, depth - h)):
                self._box("IfcWall", f"L{level} partition {i} {y0:.0f}", (x - h, y0, z), (x + h, y1, top), storey)
        corridor = self._box("IfcSpace", f"L{level} corridor", (h, corridor_lo + h, z), (length - h, corridor_hi - h, top),
                             None)
        ifcopenshell.api.aggregate.assign_object(f, products=[corridor], relating_object=storey)
        for side, (y0, y1), wall, facade in (("S", (h, corridor_lo - h), "corridor south", "south"),
                                             ("N", (corridor_hi + h, depth - h), "corridor north", "north")):
            door_y = (corridor_lo if side == "S" else corridor_hi)
            facade_y = 0.0 if side == "S" else depth
            for i in range(n):
                x0, x1 = i * ROOM_WIDTH + h, (i + 1) * ROOM_WIDTH - h
                name = f"{level}{side}{i:02d}"
                space = self._box("IfcSpace", f"Room {name}", (x0, y0, z), (x1, y1, top), None)
                ifcopenshell.api.aggregate.assign_object(f, products=[space], relating_object=storey)
                centre = (x0 + x1) / 2
                self._hole(walls[wall], "IfcDoor", f"Door {name}", (centre - DOOR[0] / 2, door_y - h - 0.05, z),
                           (centre + DOOR[0] / 2, door_y + h + 0.05, z + DOOR[1]), storey)
                if i % WINDOW_EVERY == 0:
                    sill = z + WINDOW[2]
                    self._hole(walls[facade], "IfcWindow", f"Window {name}",
                               (centre - WINDOW[0] / 2, facade_y - h - 0.05, sill),
                               (centre + WINDOW[0] / 2, facade_y + h + 0.05, sill + WINDOW[1]), storey)
        if level == 0:
            middle = (corridor_lo + corridor_hi) / 2
            self._hole(walls["west"], "IfcDoor", "Entrance", (-h - 0.05, middle - DOOR[0] / 2, z),
                       (h + 0.05, middle + DOOR[0] / 2, z + DOOR[1]), storey)
        floor = self._box("IfcSlab", f"L{level} floor", (-h, -h, z - SLAB), (length + h, depth + h, z), storey)
        if level > 0:   # the stair opening from the storey below
            stair = self._box("IfcOpeningElement", f"L{level} stair opening",
                              (length - h - STAIR_LENGTH, corridor_lo + h, z - SLAB - 0.05),
                              (length - h, corridor_hi - h, z + 0.05))
            ifcopenshell.api.feature.add_feature(f, feature=stair, element=floor)
        if level == self.storeys - 1:
            self._box("IfcSlab", "Roof", (-h, -h, top), (length + h, depth + h, top + SLAB), storey)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out")
    parser.add_argument("--storeys", type=int, default=2)
    parser.add_argument("--rooms-per-side", type=int, default=25, help="rooms each side of the corridor per storey")
    args = parser.parse_args(argv)
    if args.storeys < 1 or args.rooms_per_side < 1:
        parser.error("--storeys and --rooms-per-side must be at least 1")
    office = Office(args.storeys, args.rooms_per_side)
    for level in range(args.storeys):
        office.storey(level)
    office.f.write(args.out)
    rooms = 2 * args.rooms_per_side * args.storeys
    print(f"{args.out}: {rooms} rooms and {args.storeys} corridors on {args.storeys} storeys, "
          f"{rooms + 1} doors, {2 * args.storeys * len(range(0, args.rooms_per_side, WINDOW_EVERY))} windows")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
