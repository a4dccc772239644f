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
    out = []
    for i in range(1, len(polygon) - 1):
        t = np.array([polygon[0], polygon[i], polygon[i + 1]])
        if np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) / 2 > MIN_AREA:
            out.append(t)
    return out


def distribute(corners, lines, owner, cells):
    """Yields (cell index, (k, 3, 3) triangles, source triangle indices) for
    every triangle in `corners` (m, 3, 3)."""
    tlo, thi = corners.min(axis=1), corners.max(axis=1)
    first = [np.clip(np.searchsorted(lines[a], tlo[:, a], side="right") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    last = [np.clip(np.searchsorted(lines[a], thi[:, a], side="left") - 1, 0, len(lines[a]) - 2) for a in range(3)]
    pieces = {}
    for t in range(len(corners)):
        block = owner[first[0][t]:last[0][t] + 1, first[1][t]:last[1][t] + 1, first[2][t]:last[2][t] + 1]
        candidates = np.unique(block)
        if len(candidates) == 1:
            pieces.setdefault(int(candidates[0]), []).append((corners[t], t))
            continue
        for c in candidates:
            polygon = clip_polygon_to_box([p.copy() for p in corners[t]], cells[c].lo, cells[c].hi)
            for piece in fan(polygon):
                pieces.setdefault(int(c), []).append((piece, t))
    for c in sorted(pieces):
        yield c, np.array([p for p, _ in pieces[c]]), np.array([t for _, t in pieces[c]])
