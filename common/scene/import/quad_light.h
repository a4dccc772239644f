// Recognises an emitter mesh that is one planar parallelogram made of two
// triangles (the only light shape portico samples: AreaLight), and recovers
// corner + s*edge1 + t*edge2 with cross(edge1, edge2) along the triangles'
// geometric normal, i.e. towards the side that emits.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/math.h"

namespace portico {

struct Parallelogram {
  Vec3 corner, edge1, edge2;
};

// `positions` (xyz per vertex) and `indices` (3 per triangle) of one object.
// Returns the parallelogram, or nullopt with `problem` saying why it is not
// one ("3 triangles", "the triangles do not share an edge", ...). Shared
// corners may be one vertex or two equal ones (files without shared vertices).
std::optional<Parallelogram> parallelogramFromTriangles(const std::vector<float>& positions,
                                                        const std::vector<uint32_t>& indices, std::string& problem);

}  // namespace portico
