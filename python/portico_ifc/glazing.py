"""Which cells are outdoors, and where a window's glass goes as a thin pane.

Outdoors: the air cells on the building's padded bounds and every air cell
joined to them by portals between air cells. Wall cores and voids reached
only through rooms stay indoor air.

A window's glass is modelled as one or more thin solids (double glazing:
two), somewhere in the depth of its wall. portico's glass is a single thin
sheet, and daylight enters at the opening (the portal between the window's
indoor and outdoor cells), where its photons start: so the pane is one
rectangle, the window's hole on the opening's plane, INSET inside the
indoor cell (docs/daylight.md, "Glass"). A window between two indoor cells
gets its pane on its glass's own middle plane.
"""

from dataclasses import dataclass

import numpy as np

from . import cell_partition as cp
from .ifc_model import Opening

INSET = 1e-3        # metres: from the opening into the indoor cell
OFF_FACE = 2e-3     # metres: a pane on its glass's plane keeps this from cell faces


@dataclass
class Pane:
    window: str
    corners: np.ndarray       # (4, 3): a rectangle across `axis`
    transmittance: tuple
    at_opening: bool          # on an opening to the outdoors (else on its glass's plane)
    curtain: bool = False     # a curtain wall's plate


def outdoor_cells(cells, portals, outer_lo, outer_hi):
    """Indices of the air cells that are outdoors."""
    on_bounds = [i for i, c in enumerate(cells) if c.label == cp.AIR and
                 (np.any(np.isclose(c.lo, outer_lo)) or np.any(np.isclose(c.hi, outer_hi)))]
    neighbours = {}
    for p in portals:
        if cells[p.cell_a].label == cp.AIR and cells[p.cell_b].label == cp.AIR:
            neighbours.setdefault(p.cell_a, []).append(p.cell_b)
            neighbours.setdefault(p.cell_b, []).append(p.cell_a)
    outdoor, todo = set(on_bounds), list(on_bounds)
    while todo:
        for n in neighbours.get(todo.pop(), ()):
            if n not in outdoor:
                outdoor.add(n)
                todo.append(n)
    return outdoor


def _rectangle(axis, plane, lo, hi):
    u, v = [a for a in range(3) if a != axis]
    corners = np.zeros((4, 3))
    corners[:, axis] = plane
    corners[:, u] = [lo[u], hi[u], hi[u], lo[u]]
    corners[:, v] = [lo[v], lo[v], hi[v], hi[v]]
    return corners


def _opening_face(hole, glass_middle, outdoor, portals, lines, cell_of_point):
    """(plane, indoor cell, portal) of the face between an indoor and an
    outdoor cell on the line through the hole's centre across its host, the
    one nearest the glass; None where that line meets no such face."""
    axis = hole.across
    u, v = [a for a in range(3) if a != axis]
    centre = (hole.lo + hole.hi) / 2
    reach = (hole.hi[axis] - hole.lo[axis]) / 2 + 0.3
    inner = lines[axis][(lines[axis] > centre[axis] - reach) & (lines[axis] < centre[axis] + reach)]
    stops = np.concatenate([[centre[axis] - reach], inner, [centre[axis] + reach]])
    path = []
    for x in (stops[:-1] + stops[1:]) / 2:
        p = centre.copy()
        p[axis] = x
        path.append(cell_of_point(p))
    found = []
    for a, b, plane in zip(path[:-1], path[1:], stops[1:-1]):
        if a is None or b is None or (a in outdoor) == (b in outdoor):
            continue
        indoor = b if a in outdoor else a
        for p in portals:
            if (p.axis == axis and abs(p.plane - plane) < 1e-9 and {p.cell_a, p.cell_b} == {a, b} and
                    all(p.lo[w] - 1e-3 <= centre[w] <= p.hi[w] + 1e-3 for w in (u, v))):
                found.append((abs(plane - glass_middle), plane, indoor, p))
    return min(found, key=lambda f: f[0])[1:] if found else None


def _glass_and_hole(g, holes):
    """The glass's box and the hole it fills: a window filling no opening element has its glass as the hole."""
    corners = g.glass.corners().reshape(-1, 3)
    glass_lo, glass_hi = corners.min(axis=0), corners.max(axis=0)
    hole = holes.get(g.guid) or Opening("window", g.name, glass_lo, glass_hi, across=int(np.argmin(glass_hi - glass_lo)))
    return glass_lo, glass_hi, hole


def panes_on_glass(glazings, openings):
    """(panes, windows without a pane) for a building without cells (rooms
    found later, room_cells.h): each glass as one pane on its glass's middle
    plane, within its hole. The pane closes the hole for the room finder, as
    a window does."""
    holes = {o.filler: o for o in openings if o.kind == "window"}
    panes, missed = [], []
    for g in glazings:
        glass_lo, glass_hi, hole = _glass_and_hole(g, holes)
        axis = hole.across
        lo, hi = np.maximum(glass_lo, hole.lo), np.minimum(glass_hi, hole.hi)
        u, v = [a for a in range(3) if a != axis]
        if lo[u] >= hi[u] or lo[v] >= hi[v]:
            missed.append(g.name)
            continue
        middle = (glass_lo[axis] + glass_hi[axis]) / 2
        panes.append(Pane(g.name, _rectangle(axis, middle, lo, hi), g.transmittance, False, g.curtain))
    return panes, missed


def window_panes(glazings, openings, cells, outdoor, portals, lines, cell_of_point):
    """(panes, windows without a pane): one pane per glazed window."""
    holes = {o.filler: o for o in openings if o.kind == "window"}
    panes, missed = [], []
    for g in glazings:
        glass_lo, glass_hi, hole = _glass_and_hole(g, holes)
        axis = hole.across
        middle = (glass_lo[axis] + glass_hi[axis]) / 2
        face = _opening_face(hole, middle, outdoor, portals, lines, cell_of_point)
        if face is not None:
            plane, indoor, portal = face
            lo, hi = np.maximum(portal.lo, hole.lo), np.minimum(portal.hi, hole.hi)
            towards_indoor = 1.0 if cells[indoor].hi[axis] > plane + INSET else -1.0
            at = plane + towards_indoor * INSET
        else:
            lo, hi = np.maximum(glass_lo, hole.lo), np.minimum(glass_hi, hole.hi)
            at = middle
            near = lines[axis][np.abs(lines[axis] - at) < OFF_FACE]
            if len(near):
                at = near[0] + (OFF_FACE if at >= near[0] else -OFF_FACE)
        u, v = [a for a in range(3) if a != axis]
        if lo[u] >= hi[u] or lo[v] >= hi[v]:
            missed.append(g.name)
            continue
        panes.append(Pane(g.name, _rectangle(axis, at, lo, hi), g.transmittance, face is not None, g.curtain))
    return panes, missed
