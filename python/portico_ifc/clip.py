"""Splits triangles among box cells: a triangle inside one cell goes whole,
one crossing cell faces is clipped to each cell it crosses (Sutherland-
Hodgman against the six planes) and the pieces fanned back into triangles,
keeping the winding."""

import numpy as np

MIN_AREA = 1e-10   # square metres: slivers below this are dropped


def clip_polygon_to_box(polygon, lo, hi):
    for axis in range(3):
        for bound, keep_below in ((lo[axis], False), (hi[axis], True)):
            if len(polygon) == 0:
                return polygon
            result = []
            for i, current in enumerate(polygon):
                previous = polygon[i - 1]
                d_cur = (bound - current[axis]) if keep_below else (current[axis] - bound)
                d_prev = (bound - previous[axis]) if keep_below else (previous[axis] - bound)
                if d_cur >= 0:
                    if d_prev < 0:
                        result.append(previous + (current - previous) * (d_prev / (d_prev - d_cur)))
                    result.append(current)
                elif d_prev >= 0:
                    result.append(previous + (current - previous) * (d_prev / (d_prev - d_cur)))
            for point in result:
                point[axis] = min(max(point[axis], lo[axis]), hi[axis])
            polygon = result
    return polygon


def fan_all(polygons):
    """The fans of many polygons at once: (k, 3, 3) triangles, polygon by
    polygon, slivers dropped, and for each the index of its polygon."""
    polygons = [np.asarray(p) for p in polygons]
    counts = np.array([max(0, len(p) - 2) for p in polygons], dtype=np.int64)
    if counts.sum() == 0:
        return np.zeros((0, 3, 3)), np.zeros(0, dtype=np.int64)
    apex = np.concatenate([np.broadcast_to(p[0], (n, 3)) for p, n in zip(polygons, counts) if n])
    second = np.concatenate([p[1:-1] for p, n in zip(polygons, counts) if n])
    third = np.concatenate([p[2:] for p, n in zip(polygons, counts) if n])
    triangles = np.stack([apex, second, third], axis=1)
    area = np.linalg.norm(np.cross(second - apex, third - apex), axis=1) / 2
    keep = area > MIN_AREA
    return triangles[keep], np.repeat(np.arange(len(polygons)), counts)[keep]


def distribute(corners, lines, owner, cells):
    """Yields (cell index, (k, 3, 3) triangles, source triangle indices) for
    every triangle in `corners` (m, 3, 3)."""
    tlo, thi = corners.min(axis=1), corners.max(axis=1)
    first = [np.clip(np.searchsorted(lines[a], tlo[:, a], side="right") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    last = [np.clip(np.searchsorted(lines[a], thi[:, a], side="left") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    # A triangle within one grid box goes whole to that box's cell: decided
    # for all of them at once. Only the others are clipped one by one, and
    # their pieces fanned all at once.
    single = np.all([first[a] == last[a] for a in range(3)], axis=0)
    whole_cell = np.where(single, owner[first[0], first[1], first[2]], -1)
    polygons, polygon_cell, polygon_source = [], [], []
    for t in np.nonzero(~single)[0]:
        block = owner[first[0][t]:last[0][t] + 1, first[1][t]:last[1][t] + 1, first[2][t]:last[2][t] + 1]
        candidates = np.unique(block)
        if len(candidates) == 1:
            whole_cell[t] = candidates[0]
            continue
        for c in candidates:
            polygons.append(clip_polygon_to_box([p.copy() for p in corners[t]], cells[c].lo, cells[c].hi))
            polygon_cell.append(int(c))
            polygon_source.append(t)
    pieces, of_polygon = fan_all(polygons)
    piece_cell = np.array(polygon_cell, dtype=np.int64)[of_polygon]
    piece_source = np.array(polygon_source, dtype=np.int64)[of_polygon]
    for c in np.union1d(piece_cell, whole_cell[whole_cell >= 0]).tolist():
        whole = np.nonzero(whole_cell == c)[0]
        clipped = np.nonzero(piece_cell == c)[0]
        triangles = np.concatenate([corners[whole], pieces[clipped]])
        source = np.concatenate([whole, piece_source[clipped]])
        order = np.argsort(source, kind="stable")      # the triangles' order, as one by one
        yield c, triangles[order], source[order]
