"""Lamps and cameras for the spaces of an IFC model.

Lamps, given to the importer in lumens (docs/photometric-lights.md): one
quad per IfcLightFixture (IFC2x3: IfcFlowTerminal typed as a light
fixture), under the fixture, with the luminous flux and colour temperature
its property sets give, else its wattage times FIXTURE_EFFICACY (lm/W),
else FIXTURE_LUMENS, at FIXTURE_KELVIN by default; or, where the model has
none (or with --lights panels), one ceiling panel per space, centred over
the space's largest cell, of area PANEL_FRACTION of the space's floor area,
emitting PANEL_LUMENS_PER_M2 per m2 of that floor in PANEL_COLOUR (the
generated buildings' ceiling panels' colour and, at 4 % of the floor,
their radiance). Every lamp emits downwards.

Cameras: one per space, at eye height over the centre of its largest cell,
looking across the space towards the far corner of its box.
"""

import math

import numpy as np

from .solid_queries import first_hit_along, inside_mesh

PANEL_FRACTION = 0.04
PANEL_COLOUR = (12.0, 11.0, 9.5)
PANEL_LUMENS_PER_M2 = 250.0
FIXTURE_EFFICACY = 100.0      # lm/W of an LED luminaire
FIXTURE_LUMENS = 3000.0
FIXTURE_KELVIN = 4000.0
EYE_HEIGHT = 1.6
BELOW_CEILING = 0.05


def _largest_cell(cells, label):
    own = [i for i, c in enumerate(cells) if c.label == label]
    return max(own, key=lambda i: float(np.prod(cells[i].hi - cells[i].lo))) if own else None


def floor_area(space):
    """Horizontal area of the space's upward-facing bottom: the area of
    triangles whose normal points down out of the solid, projected."""
    c = space.mesh.corners()
    n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    return float(np.abs(n[:, 1]).sum() / 4)    # floor and ceiling each count half of |n_y| / 2


def _floor_and_ceiling(space, x, z):
    lo, hi = space.mesh.bounds()
    probe = np.array([[x, (lo[1] + hi[1]) / 2, z]])
    floor = first_hit_along(probe, space.mesh, axis=1, upward=False)[0]
    ceiling = first_hit_along(probe, space.mesh, axis=1, upward=True)[0]
    return (lo[1] if math.isnan(floor) else floor), (hi[1] if math.isnan(ceiling) else ceiling)


def _quad_down(cx, y, cz, half_x, half_z):
    """Corners of a horizontal quad whose front (the winding's normal) faces -y."""
    return [[cx - half_x, y, cz - half_z], [cx + half_x, y, cz - half_z],
            [cx + half_x, y, cz + half_z], [cx - half_x, y, cz + half_z]]


def space_panels(spaces, cells):
    lamps = []
    for index, space in enumerate(spaces):
        c = _largest_cell(cells, index)
        if c is None:
            continue
        cell = cells[c]
        cx, cz = (cell.lo[0] + cell.hi[0]) / 2, (cell.lo[2] + cell.hi[2]) / 2
        side = math.sqrt(PANEL_FRACTION * max(floor_area(space), 1.0))
        half_x = min(side, 0.8 * (cell.hi[0] - cell.lo[0])) / 2
        half_z = min(side, 0.8 * (cell.hi[2] - cell.lo[2])) / 2
        # Under the lowest point of the ceiling over the panel (roofs slope).
        ceiling = min(_floor_and_ceiling(space, cx + sx * half_x, cz + sz * half_z)[1]
                      for sx in (-1, 0, 1) for sz in (-1, 0, 1))
        y = min(ceiling, cell.hi[1]) - BELOW_CEILING
        lamps.append({"name": f"lamp {space.name}", "cell": c, "quad": _quad_down(cx, y, cz, half_x, half_z),
                      "lumens": PANEL_LUMENS_PER_M2 * max(floor_area(space), 1.0), "colour": list(PANEL_COLOUR)})
    return lamps


def fixture_lamps(fixtures, cells=None, cell_of_point=None):
    """A lamp under each fixture, within the cell holding it; without cells
    (rooms found later) as wide as the fixture."""
    lamps = []
    for fixture in fixtures:
        cx, cz = (fixture.lo[0] + fixture.hi[0]) / 2, (fixture.lo[2] + fixture.hi[2]) / 2
        y = fixture.lo[1] - 0.01
        half_x, half_z = (fixture.hi[0] - fixture.lo[0]) / 2, (fixture.hi[2] - fixture.lo[2]) / 2
        c = None
        if cells is not None:
            c = cell_of_point(np.array([cx, y, cz]))
            if c is None:
                continue
            cell = cells[c]
            half_x = min(half_x, cx - cell.lo[0], cell.hi[0] - cx) * 0.95
            half_z = min(half_z, cz - cell.lo[2], cell.hi[2] - cz) * 0.95
        lumens = fixture.lumens or (fixture.watts * FIXTURE_EFFICACY if fixture.watts else FIXTURE_LUMENS)
        lamp = {"name": f"fixture {fixture.name}", "quad": _quad_down(cx, y, cz, max(0.05, half_x), max(0.05, half_z)),
                "lumens": lumens, "colour_temperature": fixture.kelvin or FIXTURE_KELVIN}
        if c is not None:
            lamp["cell"] = c
        lamps.append(lamp)
    return lamps


def space_cameras(spaces, cells):
    cameras = []
    for index, space in enumerate(spaces):
        own = sorted((i for i, c in enumerate(cells) if c.label == index),
                     key=lambda i: -float(np.prod(cells[i].hi - cells[i].lo)))
        lo, hi = space.mesh.bounds()
        for c in own:
            cell = cells[c]
            cx, cz = (cell.lo[0] + cell.hi[0]) / 2, (cell.lo[2] + cell.hi[2]) / 2
            floor, ceiling = _floor_and_ceiling(space, cx, cz)
            y = min(floor + EYE_HEIGHT, (floor + ceiling) / 2 if ceiling - floor < EYE_HEIGHT + 0.3 else 1e9)
            y = min(max(y, cell.lo[1] + 0.05), cell.hi[1] - 0.05)
            origin = np.array([cx, y, cz])
            if not inside_mesh(origin[None, :], space.mesh)[0]:
                continue
            corners = [np.array([x, floor + 1.0, z]) for x in (lo[0], hi[0]) for z in (lo[2], hi[2])]
            target = max(corners, key=lambda p: (float(np.hypot(p[0] - cx, p[2] - cz)), tuple(p)))
            cameras.append(_camera(space.name, origin, target))
            break
        else:
            camera = _camera_anywhere(space, own, cells)
            if camera is not None:
                cameras.append(camera)
    return cameras


def _camera(name, origin, target):
    return {"name": name, "origin": [float(x) for x in origin], "target": [float(x) for x in target],
            "up": [0, 1, 0], "fov_y_deg": 70, "width": 512, "height": 384}


def _camera_anywhere(space, own, cells):
    """A space none of whose cells' centres lies inside it (an L or a ring
    drawn as one space): the camera at eye height over the point of a 9 x 9
    grid over its box, inside it and in one of its cells, nearest the box's
    centre, looking at the box's centre."""
    lo, hi = space.mesh.bounds()
    centre = (lo + hi) / 2
    candidates = []
    for x in np.linspace(lo[0], hi[0], 11)[1:-1]:
        for z in np.linspace(lo[2], hi[2], 11)[1:-1]:
            floor, ceiling = _floor_and_ceiling(space, x, z)
            if not np.isfinite(floor) or not np.isfinite(ceiling):
                continue
            y = min(floor + EYE_HEIGHT, (floor + ceiling) / 2)
            point = np.array([x, y, z])
            if any(np.all(point > cells[c].lo) and np.all(point < cells[c].hi) for c in own):
                candidates.append((float(np.hypot(x - centre[0], z - centre[2])), x, z, point))
    for _, _, _, point in sorted(candidates, key=lambda c: c[:3]):
        if inside_mesh(point[None, :], space.mesh)[0]:
            target = np.array([centre[0], point[1], centre[2]])
            if np.hypot(*(target - point)[[0, 2]]) < 0.5:
                target = np.array([hi[0], point[1], hi[2]])
            return _camera(space.name, point, target)
    return None
