// What makes a portal polygon usable, shared by the building.json reader,
// the scene store writer and the store validation (`portico scene info`).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico {

// Portals of one cell at most: every ray tests its cell's portals, so a cell
// with a million of them (one door repeated) makes leases that never end.
// A voxel cell has 6; a hall with a door every metre of a 500 m perimeter, 500.
constexpr uint32_t kMaxPortalsPerCell = 4096;

// Newell's normal of a polygon: robust for any planar polygon (its length is
// twice the area), zero for a degenerate one.
Vec3 newellNormal(const std::vector<Vec3>& polygon);

// Empty when `polygon` is a usable portal (at least 3 finite points, planar
// and convex within a tolerance relative to its size), otherwise the
// problem, phrased to follow "polygon ", e.g. "is not planar (...)".
std::string portalShapeProblem(const std::vector<Vec3>& polygon);

// How far a point may lie off a cell's box and still count as on it:
// coordinates computed by an importer or generator may be a few ulps off.
float boxTolerance(const Bounds3& box);

// Empty when every point of `polygon` lies on one face of `box` (within
// boxTolerance): a portal is where its cell's box meets the neighbour's, so
// a ray crossing it leaves the cell. Otherwise the problem, phrased to
// follow "polygon ", e.g. "lies inside the box, not on a face (...)".
std::string portalBoundaryProblem(const Bounds3& box, const std::vector<Vec3>& polygon);

}  // namespace portico
