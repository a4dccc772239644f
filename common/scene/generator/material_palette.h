// The materials of the generated buildings (the demo and the presets): each
// name with its colours, defined once. A generator adds the entries it uses,
// in its own order (a material's id is its place in the store).
#pragma once

#include <cstdint>

#include "common/math.h"
#include "common/scene/store/scene_store.h"

namespace portico::palette {

struct PaletteMaterial {
  const char* name;
  Vec3 albedo;
  Vec3 emission{0.0f};
  // Lamps and ceilings: the view from above looks through them into the
  // rooms, which they still light.
  bool hiddenFromCamera = false;
};

// Warm white ceiling panels.
inline constexpr Vec3 kLightRadiance(12.0f, 11.0f, 9.5f);

// Shells.
inline constexpr PaletteMaterial kWallWhite{"wall-white", Vec3(0.75f, 0.74f, 0.70f)};
inline constexpr PaletteMaterial kWallBlue{"wall-blue", Vec3(0.42f, 0.52f, 0.70f)};
inline constexpr PaletteMaterial kWallTerracotta{"wall-terracotta", Vec3(0.72f, 0.45f, 0.34f)};
inline constexpr PaletteMaterial kWallSage{"wall-sage", Vec3(0.52f, 0.64f, 0.50f)};
inline constexpr PaletteMaterial kFloorWood{"floor-wood", Vec3(0.55f, 0.42f, 0.30f)};
inline constexpr PaletteMaterial kFloorTiles{"floor-tiles", Vec3(0.45f, 0.45f, 0.43f)};
inline constexpr PaletteMaterial kConcrete{"concrete", Vec3(0.55f, 0.54f, 0.52f)};
inline constexpr PaletteMaterial kCeiling{"ceiling", Vec3(0.80f), Vec3(0.0f), true};
inline constexpr PaletteMaterial kLight{"light", Vec3(0.0f), kLightRadiance, true};

// Furniture.
inline constexpr PaletteMaterial kWood{"wood", Vec3(0.50f, 0.36f, 0.22f)};
inline constexpr PaletteMaterial kDarkWood{"dark-wood", Vec3(0.30f, 0.20f, 0.12f)};
inline constexpr PaletteMaterial kMetalGrey{"metal-grey", Vec3(0.50f, 0.50f, 0.52f)};
// The same white under two names: the demo's cabinets, the library's laminate.
inline constexpr Vec3 kFurnitureWhite(0.78f, 0.77f, 0.74f);
inline constexpr PaletteMaterial kCabinetWhite{"cabinet-white", kFurnitureWhite};
inline constexpr PaletteMaterial kLaminateWhite{"laminate-white", kFurnitureWhite};
inline constexpr PaletteMaterial kScreen{"screen", Vec3(0.04f, 0.04f, 0.05f)};
inline constexpr PaletteMaterial kFabrics[3] = {{"fabric-red", Vec3(0.65f, 0.18f, 0.16f)},
                                                {"fabric-blue", Vec3(0.18f, 0.28f, 0.60f)},
                                                {"fabric-cream", Vec3(0.80f, 0.76f, 0.66f)}};
inline constexpr PaletteMaterial kBooks[3] = {{"book-green", Vec3(0.20f, 0.45f, 0.25f)},
                                              {"book-yellow", Vec3(0.80f, 0.65f, 0.20f)},
                                              {"book-red", Vec3(0.55f, 0.12f, 0.10f)}};
inline constexpr PaletteMaterial kLeaf{"leaf", Vec3(0.16f, 0.42f, 0.14f)};
inline constexpr PaletteMaterial kTerracotta{"terracotta", Vec3(0.62f, 0.33f, 0.22f)};

// Adds a palette entry to the store; returns its material id.
inline uint32_t add(SceneStoreWriter& writer, const PaletteMaterial& material) {
  return writer.addMaterial(material.name, material.albedo, material.emission, material.hiddenFromCamera);
}

}  // namespace portico::palette
