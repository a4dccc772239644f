"""Point-in-solid and axis-ray queries on closed triangle meshes, vectorised.

A point is inside a closed mesh when a ray from it crosses the mesh an odd
number of times. Rays run along a coordinate axis, so a crossing is a 2-D
point-in-triangle test in the other two axes plus a comparison along the
axis; the parity does not depend on the triangles' orientation, so mirrored
(inside-out) instances count as solids too.
"""

import numpy as np

# Query points are nudged off the exact coordinates where models put their
# edges and vertices (whole centimetres), so that a ray never runs through
# an edge shared by two triangles and is counted twice or not at all.
JITTER = np.array([1.234567e-4, 2.345671e-4, 3.456712e-4])
_CHUNK = 4_000_000   # points x triangles per numpy step
_RAY_CHUNK = 3_000_000   # rays x triangles per numpy step of nearest_hits
_PARALLEL = 1e-9         # |det| below this: the ray runs along the triangle


def _other_axes(axis):
    return [a for a in range(3) if a != axis]


def _crossings(points, corners, axis, upward=True):
    """(n_points, n_triangles) bool: does the ray from each point along +axis
    (or -axis) cross each triangle; and the axis coordinate of the crossing."""
    u, v = _other_axes(axis)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    pu, pv = points[:, u][:, None], points[:, v][:, None]

    def edge(p, q):
        return (q[:, u] - p[:, u])[None, :] * (pv - p[:, v][None, :]) - (q[:, v] - p[:, v])[None, :] * (pu - p[:, u][None, :])

    e0, e1, e2 = edge(a, b), edge(b, c), edge(c, a)
    inside = ((e0 > 0) & (e1 > 0) & (e2 > 0)) | ((e0 < 0) & (e1 < 0) & (e2 < 0))
    area = e0 + e1 + e2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        w_a, w_b, w_c = e1 / area, e2 / area, e0 / area
        height = w_a * a[:, axis][None, :] + w_b * b[:, axis][None, :] + w_c * c[:, axis][None, :]
        ahead = height > points[:, axis][:, None] if upward else height < points[:, axis][:, None]
    return inside & ahead, height


def _near_triangles(mesh, points, axis):
    """Triangles whose footprint (across the axis) meets the points' footprint."""
    u, v = _other_axes(axis)
    lo, hi = points.min(axis=0), points.max(axis=0)
    return _triangles_over(mesh, axis, lo[u], hi[u], lo[v], hi[v])


def _triangles_over(mesh, axis, u_lo, u_hi, v_lo, v_hi):
    """Triangles whose footprint (across the axis) meets the rectangle."""
    u, v = _other_axes(axis)
    tlo, thi = mesh.triangle_bounds()
    keep = (thi[:, u] >= u_lo) & (tlo[:, u] <= u_hi) & (thi[:, v] >= v_lo) & (tlo[:, v] <= v_hi)
    return mesh.corners()[keep]


def inside_mesh(points, mesh, axis=0):
    """(n,) bool: which points lie inside the closed mesh.

    Points on one line along the axis share a ray: its crossings are
    computed once, and each point counts those ahead of it (a cell face
    across the axis holds rows of hundreds of such points)."""
    points = np.asarray(points, dtype=np.float64) + JITTER
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    u, v = _other_axes(axis)
    # Rows by their (u, v) coordinates; one-dimensional uniques are much
    # faster than np.unique(axis=0), and their ends are the footprint.
    us, u_of_point = np.unique(points[:, u], return_inverse=True)
    vs, v_of_point = np.unique(points[:, v], return_inverse=True)
    corners = _triangles_over(mesh, axis, us[0], us[-1], vs[0], vs[-1])
    if len(corners) == 0:
        return np.zeros(len(points), dtype=bool)
    keys, ray_of_point = np.unique(u_of_point.reshape(-1) * len(vs) + v_of_point.reshape(-1), return_inverse=True)
    ray_of_point = ray_of_point.reshape(-1)
    origins = np.zeros((len(keys), 3))
    origins[:, u], origins[:, v] = us[keys // len(vs)], vs[keys % len(vs)]
    rays = keys
    step = max(1, _CHUNK // len(corners))
    hit_ray, hit_height = [], []
    for start in range(0, len(rays), step):
        rows, heights = _ray_crossings(origins[start:start + step], corners, axis)
        hit_ray.append(rows + start)
        hit_height.append(heights)
    hit_ray, hit_height = np.concatenate(hit_ray), np.concatenate(hit_height)
    # Each ray's crossing heights in one row, padded with -inf (never ahead).
    per_ray = np.bincount(hit_ray, minlength=len(rays))
    slot = np.arange(len(hit_ray)) - np.repeat(np.cumsum(per_ray) - per_ray, per_ray)
    table = np.full((len(rays), max(1, int(per_ray.max(initial=0)))), -np.inf)
    table[hit_ray, slot] = hit_height
    ahead = (table[ray_of_point] > points[:, axis][:, None]).sum(axis=1)
    return ahead % 2 == 1


def _ray_crossings(origins, corners, axis):
    """The (ray, height) pairs where the line along the axis through each
    origin crosses a triangle: same arithmetic as _crossings, with the
    height computed only where the footprint test passes."""
    u, v = _other_axes(axis)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    pu, pv = origins[:, u][:, None], origins[:, v][:, None]

    def edge(p, q):
        return (q[:, u] - p[:, u])[None, :] * (pv - p[:, v][None, :]) - (q[:, v] - p[:, v])[None, :] * (pu - p[:, u][None, :])

    e0, e1 = edge(a, b), edge(b, c)
    same = ((e0 > 0) & (e1 > 0)) | ((e0 < 0) & (e1 < 0))
    rows, cols = np.nonzero(same)
    e0, e1 = e0[rows, cols], e1[rows, cols]
    p, q = c[cols], a[cols]
    e2 = (q[:, u] - p[:, u]) * (origins[rows, v] - p[:, v]) - (q[:, v] - p[:, v]) * (origins[rows, u] - p[:, u])
    inside = ((e0 > 0) & (e2 > 0)) | ((e0 < 0) & (e2 < 0))
    rows, cols, e0, e1, e2 = rows[inside], cols[inside], e0[inside], e1[inside], e2[inside]
    area = e0 + e1 + e2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        w_a, w_b, w_c = e1 / area, e2 / area, e0 / area
        height = w_a * a[cols, axis] + w_b * b[cols, axis] + w_c * c[cols, axis]
    return rows, height


def first_hit_along(points, mesh, axis, upward=True):
    """(n,) float: the axis coordinate of the nearest crossing of the mesh from
    each point along +axis (upward) or -axis; NaN where there is none."""
    points = np.asarray(points, dtype=np.float64) + JITTER
    corners = _near_triangles(mesh, points, axis)
    result = np.full(len(points), np.nan)
    if len(corners) == 0:
        return result
    hits, height = _crossings(points, corners, axis, upward)
    masked = np.where(hits, height, np.inf if upward else -np.inf)
    best = masked.min(axis=1) if upward else masked.max(axis=1)
    return np.where(np.isfinite(best), best, np.nan)


def nearest_hits(origins, directions, corners):
    """(n,) distance along each ray to the nearest triangle it crosses, either
    side (Moeller-Trumbore); inf where it crosses none. Component by
    component: numpy's cross and einsum are slow on a last axis of 3."""
    ax, ay, az = corners[:, 0, 0], corners[:, 0, 1], corners[:, 0, 2]
    e1 = corners[:, 1] - corners[:, 0]
    e2 = corners[:, 2] - corners[:, 0]
    e1x, e1y, e1z, e2x, e2y, e2z = e1[:, 0], e1[:, 1], e1[:, 2], e2[:, 0], e2[:, 1], e2[:, 2]
    nearest = np.full(len(origins), np.inf)
    step = max(1, _RAY_CHUNK // max(1, len(corners)))
    for start in range(0, len(origins), step):
        o, d = origins[start:start + step], directions[start:start + step]
        dx, dy, dz = d[:, 0:1], d[:, 1:2], d[:, 2:3]
        px, py, pz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
        det = px * e1x + py * e1y + pz * e1z
        sx, sy, sz = o[:, 0:1] - ax, o[:, 1:2] - ay, o[:, 2:3] - az
        qx, qy, qz = sy * e1z - sz * e1y, sz * e1x - sx * e1z, sx * e1y - sy * e1x
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            u = (sx * px + sy * py + sz * pz) * inv
            v = (dx * qx + dy * qy + dz * qz) * inv
            t = (qx * e2x + qy * e2y + qz * e2z) * inv
            ok = (np.abs(det) > _PARALLEL) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
        nearest[start:start + step] = np.where(ok, t, np.inf).min(axis=1)
    return nearest
