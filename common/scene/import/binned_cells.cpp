// Triangles binned per cell: pass 1 counts, pass 2 fills one flat reference
// array, then each cell is assembled and written on its own.
#include "common/scene/import/binned_cells.h"

#include <vector>

namespace portico {

namespace {

// A reference to one input triangle: object index and triangle index.
uint64_t packReference(size_t object, size_t triangle) { return (uint64_t(object) << 32) | uint64_t(triangle); }

}  // namespace

void writeBinnedCells(const ImportedScene& scene, uint32_t cellCount, const TouchedCells& touched,
                      const std::function<std::string(uint32_t)>& name,
                      const std::function<Bounds3(uint32_t)>& bounds, SceneStoreWriter& writer) {
  // Pass 1: how many triangles each cell gets. Pass 2: the references,
  // cell by cell, in input order (so the output does not depend on anything
  // but the input).
  std::vector<uint64_t> offsets(size_t{cellCount} + 1, 0);
  for (size_t o = 0; o < scene.objects.size(); ++o)
    for (size_t t = 0; t < scene.objects[o].triangleCount(); ++t)
      touched(scene.objects[o], t, [&](uint32_t cell) { ++offsets[cell + 1]; });
  for (uint32_t cell = 0; cell < cellCount; ++cell) offsets[cell + 1] += offsets[cell];
  std::vector<uint64_t> references(offsets.back());
  {
    std::vector<uint64_t> next(offsets.begin(), offsets.end() - 1);
    for (size_t o = 0; o < scene.objects.size(); ++o)
      for (size_t t = 0; t < scene.objects[o].triangleCount(); ++t)
        touched(scene.objects[o], t,
                [&](uint32_t cell) { references[next[cell]++] = packReference(o, t); });
  }

  // Each cell's vertices: an input vertex is copied once per cell; `stamp`
  // says for which cell `remap` holds its index (no clearing between cells).
  std::vector<uint64_t> firstVertex(scene.objects.size() + 1, 0);
  for (size_t o = 0; o < scene.objects.size(); ++o)
    firstVertex[o + 1] = firstVertex[o] + scene.objects[o].positions.size() / 3;
  std::vector<uint32_t> stamp(firstVertex.back(), 0), remap(firstVertex.back(), 0);
  for (uint32_t id = 0; id < cellCount; ++id) {
    CellContent cell;
    cell.id = id;
    cell.name = name(id);
    cell.bounds = bounds(id);
    bool textured = false;
    for (uint64_t r = offsets[id]; r < offsets[id + 1]; ++r) {
      const size_t o = references[r] >> 32, t = references[r] & 0xffffffffu;
      const ImportedObject& object = scene.objects[o];
      for (int corner = 0; corner < 3; ++corner) {
        const uint32_t local = object.indices[3 * t + corner];
        const uint64_t global = firstVertex[o] + local;
        if (stamp[global] != id + 1) {
          stamp[global] = id + 1;
          remap[global] = static_cast<uint32_t>(cell.positions.size() / 3);
          cell.positions.insert(cell.positions.end(), &object.positions[3 * size_t{local}],
                                &object.positions[3 * size_t{local}] + 3);
          // uvs for every vertex (zeros for untextured objects), dropped below if none is textured.
          const float* uv = object.uvs.empty() ? nullptr : &object.uvs[2 * size_t{local}];
          cell.uvs.insert(cell.uvs.end(), {uv ? uv[0] : 0.0f, uv ? uv[1] : 0.0f});
        }
        cell.indices.push_back(remap[global]);
      }
      cell.materials.push_back(object.material);
      textured = textured || !object.uvs.empty();
    }
    if (!textured) cell.uvs.clear();
    writer.writeCell(cell);
  }
}

}  // namespace portico
