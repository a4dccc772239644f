"""Cuts a building's padded bounds into box cells that follow its spaces.

1. Grid lines along each axis come from the spaces' boxes: where one space's
   side faces another's across a wall or slab (a gap of at most MAX_WALL),
   the line runs down the middle of the gap; elsewhere it runs OUTSET beyond
   the space's side, inside the enclosing wall. So cell faces lie inside
   walls and slabs; a line that still falls on a surface (two spaces
   touching at a wall's face) moves a few millimetres off it.
2. Each box of the grid takes the space holding its centre, or none (air:
   outside, wall cores, unmodelled voids).
3. Boxes with the same label merge greedily into larger boxes: the cells.
   A space that is not a box becomes several cells.
4. Two cells sharing a face get a portal unless the face is sealed: every
   sample point of it (SAMPLE spacing) lies inside a wall, slab, roof, ...
   The portal is the bounding rectangle of the unsealed samples, grown by a
   sample and clamped to the face: a door's or window's hole, a stair
   opening, or the whole face between two parts of one open space.
"""

from dataclasses import dataclass

import numpy as np

from .solid_queries import inside_mesh

MAX_WALL = 0.8      # metres: the widest gap between two spaces still read as one wall or slab
OUTSET = 0.05       # metres: from a space's side into its wall, where no space faces it
MERGE = 0.03        # metres: grid lines closer than this are one
SAMPLE = 0.1        # metres: spacing of the sealing test's samples
CLEARANCE = 0.006   # metres: grid lines keep at least half of this from surfaces facing along them
PAD = 1e-3          # metres: more than inside_mesh's JITTER
AIR = -1


@dataclass
class Cell:
    label: int          # space index, or AIR
    lo: np.ndarray      # (3,) metres
    hi: np.ndarray
    index_lo: tuple     # grid indices, inclusive lower, exclusive upper
    index_hi: tuple


@dataclass
class Portal:
    cell_a: int
    cell_b: int
    axis: int
    plane: float
    lo: np.ndarray      # the rectangle's corners on the plane (3,)
    hi: np.ndarray


def _lines_along(axis, spaces, outer_lo, outer_hi):
    sides = []
    for space in spaces:
        lo, hi = space.mesh.bounds()
        sides.append((lo[axis], hi[axis]))
    lows = np.array([s[0] for s in sides])
    highs = np.array([s[1] for s in sides])
    lines = [outer_lo, outer_hi]
    for h in highs:
        gaps = lows - h
        facing = gaps[(gaps > -MERGE) & (gaps <= MAX_WALL)]
        lines.append(h + facing.min() / 2 if len(facing) else h + OUTSET)
    for l in lows:
        gaps = l - highs
        facing = gaps[(gaps > -MERGE) & (gaps <= MAX_WALL)]
        lines.append(l - facing.min() / 2 if len(facing) else l - OUTSET)
    lines = sorted(x for x in lines if outer_lo <= x <= outer_hi)
    merged = [lines[0]]
    for x in lines[1:]:
        if x - merged[-1] >= MERGE:
            merged.append(x)
    merged[-1] = outer_hi
    return np.array(merged)


def _surface_planes(meshes, axis):
    """Sorted coordinates of the planes of triangles facing along `axis`."""
    planes = []
    for mesh in meshes:
        c = mesh.corners()
        n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
        facing = np.abs(n[:, axis]) > 0.999 * np.linalg.norm(n, axis=1)
        planes.append(c[facing, 0, axis])
    return np.unique(np.concatenate(planes)) if planes else np.zeros(0)


def _off_surfaces(lines, planes):
    """Moves inner lines off surfaces lying on them: a cell face on a wall's
    surface would leave the surface on one side only, up to rounding, and a
    ray crossing the face there could miss it on both."""
    moved = lines.copy()
    for i in range(1, len(lines) - 1):
        for shift in (0.0, CLEARANCE, -CLEARANCE, 2 * CLEARANCE, -2 * CLEARANCE):
            x = lines[i] + shift
            near = planes[np.searchsorted(planes, x - CLEARANCE / 2):np.searchsorted(planes, x + CLEARANCE / 2)]
            if len(near) == 0:
                moved[i] = x
                break
    return moved


def grid_lines(spaces, outer_lo, outer_hi, meshes=()):
    lines = [_lines_along(a, spaces, outer_lo[a], outer_hi[a]) for a in range(3)]
    return [_off_surfaces(lines[a], _surface_planes(meshes, a)) for a in range(3)]


def label_boxes(lines, spaces):
    """(nx, ny, nz) int array: the space holding each grid box's centre, or AIR."""
    centres = [(l[:-1] + l[1:]) / 2 for l in lines]
    grid = np.stack(np.meshgrid(*centres, indexing="ij"), axis=-1)
    points = grid.reshape(-1, 3)
    labels = np.full(len(points), AIR, dtype=np.int64)
    for index, space in enumerate(spaces):
        lo, hi = space.mesh.bounds()
        candidates = np.nonzero(np.all((points >= lo) & (points <= hi), axis=1) & (labels == AIR))[0]
        if len(candidates):
            labels[candidates[inside_mesh(points[candidates], space.mesh)]] = index
    return labels.reshape(grid.shape[:3])


def merge_boxes(labels, lines):
    """Greedy merging of equal labels: along x, then z, then y."""
    shape = labels.shape
    owner = np.full(shape, -1, dtype=np.int64)
    cells = []
    for j in range(shape[1]):
        for k in range(shape[2]):
            for i in range(shape[0]):
                if owner[i, j, k] >= 0:
                    continue
                label = labels[i, j, k]

                def free(i0, i1, j0, j1, k0, k1):
                    block = (slice(i0, i1), slice(j0, j1), slice(k0, k1))
                    return bool(np.all(labels[block] == label) and np.all(owner[block] < 0))

                i1 = i + 1
                while i1 < shape[0] and free(i1, i1 + 1, j, j + 1, k, k + 1):
                    i1 += 1
                k1 = k + 1
                while k1 < shape[2] and free(i, i1, j, j + 1, k1, k1 + 1):
                    k1 += 1
                j1 = j + 1
                while j1 < shape[1] and free(i, i1, j1, j1 + 1, k, k1):
                    j1 += 1
                owner[i:i1, j:j1, k:k1] = len(cells)
                lo = np.array([lines[0][i], lines[1][j], lines[2][k]])
                hi = np.array([lines[0][i1], lines[1][j1], lines[2][k1]])
                cells.append(Cell(int(label), lo, hi, (i, j, k), (i1, j1, k1)))
    return cells, owner


def touching_pairs(owner):
    """{(a, b, axis, plane index)} for cells a < b that share part of a grid plane."""
    pairs = set()
    for axis in range(3):
        lower = np.take(owner, np.arange(owner.shape[axis] - 1), axis=axis)
        upper = np.take(owner, np.arange(1, owner.shape[axis]), axis=axis)
        differ = np.nonzero(lower != upper)
        for index in zip(*differ):
            a, b = int(lower[index]), int(upper[index])
            pairs.add((min(a, b), max(a, b), axis, int(index[axis]) + 1))
    return sorted(pairs)


def _axis_samples(lo, hi, lines, planes):
    """Sample coordinates in [lo, hi]: every grid interval inside gets its own,
    SAMPLE apart at most, and either side of every surface plane gets one
    just off it, so that a sliver of open air between a grid line and a
    surface (a few millimetres) is sampled too."""
    inner = lines[(lines > lo) & (lines < hi)]
    bounds = np.concatenate([[lo], inner, [hi]])
    samples = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        n = max(1, int(np.ceil((b - a) / SAMPLE)))
        samples.append(a + (np.arange(n) + 0.5) * (b - a) / n)
    near = planes[(planes > lo) & (planes < hi)]
    beside = np.concatenate([near - CLEARANCE / 4, near + CLEARANCE / 4])
    samples.append(beside[(beside > lo) & (beside < hi)])
    return np.unique(np.concatenate(samples))


def _face_samples(lo, hi, axis, plane, lines, planes):
    u, v = [a for a in range(3) if a != axis]
    su = _axis_samples(lo[u], hi[u], lines[u], planes[u])
    sv = _axis_samples(lo[v], hi[v], lines[v], planes[v])
    gu, gv = np.meshgrid(su, sv, indexing="ij")
    points = np.zeros((gu.size, 3))
    points[:, axis], points[:, u], points[:, v] = plane, gu.ravel(), gv.ravel()
    return points


def _sealed(points, sealers, sealer_lo, sealer_hi):
    sealed = np.zeros(len(points), dtype=bool)
    lo, hi = points.min(axis=0) - 1e-3, points.max(axis=0) + 1e-3
    near = np.nonzero(np.all(sealer_hi >= lo, axis=1) & np.all(sealer_lo <= hi, axis=1))[0]
    columns = np.ascontiguousarray(points.T)
    for s in near:
        mesh, (mlo, mhi) = sealers[s]
        # The box test is only a prefilter: it keeps points up to PAD outside,
        # since inside_mesh nudges points (by its JITTER) before it decides; a
        # sample on a wall's foot lies on the slab's top, and the nudge puts
        # it inside the wall, not the slab.
        todo = ~sealed
        for a in range(3):      # column by column: much faster than np.all(..., axis=1)
            todo &= (columns[a] >= mlo[a] - PAD) & (columns[a] <= mhi[a] + PAD)
        if todo.any():
            sealed[todo] = inside_mesh(points[todo], mesh, axis=0)
    return sealed


def find_portals(cells, owner, lines, sealers):
    """Portals between touching cells, each on the rectangle the two boxes share."""
    planes = [_surface_planes([mesh for mesh, _ in sealers], a) for a in range(3)]
    sealer_lo = np.array([b[0] for _, b in sealers]).reshape(-1, 3)
    sealer_hi = np.array([b[1] for _, b in sealers]).reshape(-1, 3)
    portals = []
    for a, b, axis, plane_index in touching_pairs(owner):
        plane = lines[axis][plane_index]
        lo = np.maximum(cells[a].lo, cells[b].lo)
        hi = np.minimum(cells[a].hi, cells[b].hi)
        lo[axis] = hi[axis] = plane
        if cells[a].label == cells[b].label and cells[a].label != AIR:
            portals.append(Portal(a, b, axis, plane, lo, hi))      # two parts of one space
            continue
        points = _face_samples(lo, hi, axis, plane, lines, planes)
        open_points = points[~_sealed(points, sealers, sealer_lo, sealer_hi)]
        if len(open_points) == 0:
            continue
        plo = np.maximum(open_points.min(axis=0) - SAMPLE, lo)
        phi = np.minimum(open_points.max(axis=0) + SAMPLE, hi)
        plo[axis] = phi[axis] = plane
        portals.append(Portal(a, b, axis, plane, plo, phi))
    return portals


def connected_components(cell_count, portals):
    parent = list(range(cell_count))

    def root(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for p in portals:
        parent[root(p.cell_a)] = root(p.cell_b)
    return len({root(x) for x in range(cell_count)})
