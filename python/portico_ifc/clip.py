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


def fan(polygon):
    if len(polygon) < 3:
        return []
    p = np.asarray(polygon)
    triangles = np.stack([np.broadcast_to(p[0], p[1:-1].shape), p[1:-1], p[2:]], axis=1)
    area = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1) / 2
    return list(triangles[area > MIN_AREA])


def distribute(corners, lines, owner, cells):
    """Yields (cell index, (k, 3, 3) triangles, source triangle indices) for
    every triangle in `corners` (m, 3, 3)."""
    tlo, thi = corners.min(axis=1), corners.max(axis=1)
    first = [np.clip(np.searchsorted(lines[a], tlo[:, a], side="right") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    last = [np.clip(np.searchsorted(lines[a], thi[:, a], side="left") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    # A triangle within one grid box goes whole to that box's cell: decided
    # for all of them at once. Only the others are looked at one by one.
    single = np.all([first[a] == last[a] for a in range(3)], axis=0)
    whole_cell = np.where(single, owner[first[0], first[1], first[2]], -1)
    pieces = {}
    for t in np.nonzero(~single)[0]:
        block = owner[first[0][t]:last[0][t] + 1, first[1][t]:last[1][t] + 1, first[2][t]:last[2][t] + 1]
        candidates = np.unique(block)
        if len(candidates) == 1:
            whole_cell[t] = candidates[0]
            continue
        for c in candidates:
            polygon = clip_polygon_to_box([p.copy() for p in corners[t]], cells[c].lo, cells[c].hi)
            for piece in fan(polygon):
                pieces.setdefault(int(c), []).append((piece, t))
    for c in sorted(set(pieces) | set(np.unique(whole_cell[whole_cell >= 0]).tolist())):
        whole = np.nonzero(whole_cell == c)[0]
        clipped = pieces.get(c, [])
        triangles = np.concatenate([corners[whole], np.array([p for p, _ in clipped]).reshape(-1, 3, 3)])
        source = np.concatenate([whole, np.array([t for _, t in clipped], dtype=np.int64)])
        order = np.argsort(source, kind="stable")      # the triangles' order, as one by one
        yield c, triangles[order], source[order]
