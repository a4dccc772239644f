"""Closing what a model leaves open (docs/ifc-corpus.md, "Closing what the model leaves open").

A space's solid (its IfcSpace shape) is where a room's air is; its faces
should lie on walls, slabs, roofs, coverings. Where no such element bounds
a piece of a face (a floor drawn nowhere, a ceiling that stops short, a wall
left out), light leaves the building through the gap. That piece of the
space's own face becomes a closing surface instead, of a documented grey.

A face is cut into small triangles (edges at most PIECE metres); a piece is
open when, from its centre along the face's outward normal, no sealing
element lies within REACH metres (nor BEHIND metres inward, for faces drawn
a little beyond a wall's surface), and it lies in no door's, window's or
void's box (holes stay holes) and borders no other space (open plans,
galleries and stairwells stay open). Deterministic: the same model gives the
same triangles.
"""

import numpy as np

from .solid_queries import inside_mesh, nearest_hits

PIECE = 0.75         # metres: longest edge of a tested piece of a space's face
REACH = 0.5          # metres: an element this far beyond the face still bounds it
BEHIND = 0.1         # metres: ... or this far inside it
NEIGHBOUR = 0.15     # metres: a point this far out inside another space: an open boundary
HOLE_MARGIN = 0.05   # metres around a hole's box
CLOSING_ALBEDO = (0.5, 0.5, 0.5)
CLOSING_MATERIAL = "closing (space boundary)"


def _subdivided(corners, piece):
    """Triangles halved across their longest edge until every edge is at most
    `piece` (a long corridor's faces stay few pieces wide); and the index in
    `corners` each piece comes from."""
    done, done_parent = [], []
    todo, parent = corners, np.arange(len(corners))
    for _ in range(64):
        if len(todo) == 0:
            break
        edges = np.linalg.norm(todo[:, [1, 2, 0]] - todo, axis=2)       # edge k runs from corner k to k+1
        small = edges.max(axis=1) <= piece
        done.append(todo[small])
        done_parent.append(parent[small])
        big, parent, longest = todo[~small], parent[~small], edges[~small].argmax(axis=1)
        # Roll each triangle so that its longest edge runs from corner 0 to 1, then halve it there.
        rolled = big[np.arange(len(big))[:, None], (longest[:, None] + np.arange(3)[None, :]) % 3]
        a, b, c = rolled[:, 0], rolled[:, 1], rolled[:, 2]
        middle = (a + b) / 2
        todo = np.concatenate([np.stack((a, middle, c), axis=1), np.stack((middle, b, c), axis=1)])
        parent = np.tile(parent, 2)
    done.append(todo)
    done_parent.append(parent)
    return np.concatenate(done), np.concatenate(done_parent)


def _merged(corners, pieces, parent, is_open):
    """The open pieces, a face whose pieces are all open as its one triangle
    (fewer triangles for the cells to hold)."""
    total = np.bincount(parent, minlength=len(corners))
    opened = np.bincount(parent[is_open], minlength=len(corners))
    whole = (opened == total) & (total > 0)
    return np.concatenate([corners[whole], pieces[is_open & ~whole[parent]]])


def _in_boxes(points, lo, hi):
    if len(lo) == 0:
        return np.zeros(len(points), dtype=bool)
    inside = np.ones((len(points), len(lo)), dtype=bool)
    for a in range(3):
        inside &= (points[:, a, None] >= lo[None, :, a]) & (points[:, a, None] <= hi[None, :, a])
    return inside.any(axis=1)


def open_pieces(space, others, sealers, hole_lo, hole_hi):
    """(k, 3, 3): the pieces of the space's faces no sealing element bounds."""
    corners = space.mesh.corners()
    pieces, parent = _subdivided(corners, PIECE)
    normal = np.cross(pieces[:, 1] - pieces[:, 0], pieces[:, 2] - pieces[:, 0])
    length = np.linalg.norm(normal, axis=1)
    normal /= np.maximum(length, 1e-300)[:, None]
    centre = pieces.mean(axis=1)
    # Outward whatever the winding: a point just beyond an outward face lies outside the solid.
    flip = inside_mesh(centre + normal * 0.01, space.mesh)
    normal[flip] *= -1
    candidate = ~_in_boxes(centre, hole_lo - HOLE_MARGIN, hole_hi + HOLE_MARGIN) & (length > 1e-12)
    outside = centre + normal * NEIGHBOUR
    for other in others:
        lo, hi = other.mesh.bounds()
        near = candidate & np.all((outside >= lo) & (outside <= hi), axis=1)
        if near.any():
            candidate[np.nonzero(near)[0][inside_mesh(outside[near], other.mesh)]] = False
    if len(sealers):
        s_lo, s_hi = sealers.min(axis=1), sealers.max(axis=1)
        start, end = centre - normal * BEHIND, centre + normal * REACH
        order = np.argsort(parent[candidate], kind="stable")
        index = np.nonzero(candidate)[0][order]
        # Face by face: the segments of one face's pieces sweep a thin slab,
        # which few of the sealing triangles near the space meet.
        for group in np.split(index, np.nonzero(np.diff(parent[index]))[0] + 1):
            if len(group) == 0:
                continue
            lo = np.minimum(start[group].min(axis=0), end[group].min(axis=0))
            hi = np.maximum(start[group].max(axis=0), end[group].max(axis=0))
            near = np.all((s_hi >= lo) & (s_lo <= hi), axis=1)
            if near.any():
                hits = nearest_hits(start[group], normal[group], sealers[near])
                candidate[group[hits <= BEHIND + REACH]] = False
    return _merged(corners, pieces, parent, candidate)


def close_spaces(spaces, sealing_meshes, holes):
    """The closing triangles of every space and, per space, their area (m²).
    `holes`: [(lo, hi)] boxes of doors', windows' and voids' holes."""
    hole_lo = np.array([h[0] for h in holes]).reshape(-1, 3)
    hole_hi = np.array([h[1] for h in holes]).reshape(-1, 3)
    all_corners = np.concatenate([m.corners() for m in sealing_meshes]) if sealing_meshes else np.zeros((0, 3, 3))
    t_lo, t_hi = all_corners.min(axis=1), all_corners.max(axis=1)
    triangles, areas = [], []
    for i, space in enumerate(spaces):
        lo, hi = space.mesh.bounds()
        reach = BEHIND + REACH + 0.01
        near = np.all((t_hi >= lo - reach) & (t_lo <= hi + reach), axis=1)
        lo_s, hi_s = lo - NEIGHBOUR - 0.01, hi + NEIGHBOUR + 0.01
        others = [o for j, o in enumerate(spaces) if j != i and
                  np.all(o.mesh.bounds()[1] >= lo_s) and np.all(o.mesh.bounds()[0] <= hi_s)]
        pieces = open_pieces(space, others, all_corners[near], hole_lo, hole_hi)
        area = 0.5 * np.linalg.norm(np.cross(pieces[:, 1] - pieces[:, 0], pieces[:, 2] - pieces[:, 0]), axis=1).sum()
        triangles.append(pieces)
        areas.append(float(area))
    return triangles, areas
