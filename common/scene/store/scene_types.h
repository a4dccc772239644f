// Plain records of a scene store's catalogue (scene.db).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/photometry/luminous_intensity.h"
#include "common/photometry/luminous_opening.h"

namespace portico {

struct Material {
  uint32_t id = 0;
  std::string name;
  Vec3 albedo;     // linear RGB reflectance in [0,1]; Lambertian BRDF = albedo / pi
  Vec3 emission;   // RGB radiance, one-sided (front = geometric normal side)
  // Cut-away: camera rays reaching its back pass through it (it still blocks
  // and reflects light); lets a view from above show a room whose ceiling
  // (facing down) still lights it, while a camera in the room sees it.
  bool hiddenFromCamera = false;
  // An albedo texture, relative to the store directory (textures/...), or
  // empty. The albedo at a point is the texture's colour there (linear RGB)
  // times `albedo`, and the cell's uvs say where on the texture a point lies.
  std::string albedoTexture;
  bool textured() const { return !albedoTexture.empty(); }
  // Thin glass (common/transport/thin_glass.h) when any channel is above 0:
  // the tint of light passing through the pane, and the index of refraction
  // of its Fresnel reflection. A glass material has no diffuse albedo.
  Vec3 transmittance;
  float ior = 1.5f;
  bool emissive() const { return maxComponent(emission) > 0.0f; }
  bool glass() const { return maxComponent(transmittance) > 0.0f; }
};

enum class LightShape : uint8_t { Parallelogram, Triangle, Point };

// An area light: a parallelogram corner + s*edge1 + t*edge2, s,t in [0,1],
// or the triangle (corner, corner + edge1, corner + edge2), s + t <= 1.
// It emits on the side of cross(edge1, edge2). Its triangles are also part
// of its cell's geometry (with an emissive material), so rays can hit it.
//
// Or a point luminaire (LightShape::Point, docs/photometric-lights.md): the
// candela distribution `intensity` of a photometric file, from the point
// `corner`; `edge1` is its nadir (unit: vertical angle 0), `edge2` its C0
// direction (unit, perpendicular to edge1), and `radiance` the RGB
// intensity per candela (W sr^-1 per channel per cd). It has no triangles;
// a camera sees its luminous `opening` (centred on the point) with the
// luminance I / A_projected, but light and photons pass through it: they
// leave the point as before.
struct AreaLight {
  uint32_t id = 0;
  uint32_t cell = 0;
  LightShape shape = LightShape::Parallelogram;
  Vec3 corner, edge1, edge2;
  Vec3 radiance;
  std::shared_ptr<const LuminousIntensity> intensity;   // a point luminaire's; null for area lights
  LuminousOpening opening;                              // a point luminaire's; none for area lights
  bool isTriangle() const { return shape == LightShape::Triangle; }
  bool isPoint() const { return shape == LightShape::Point; }
  // The emitting side; a point luminaire's nadir.
  Vec3 normal() const { return isPoint() ? edge1 : normalize(cross(edge1, edge2)); }
  float area() const {
    if (isPoint()) return 0.0f;
    return isTriangle() ? 0.5f * length(cross(edge1, edge2)) : length(cross(edge1, edge2));
  }
  // Phi = pi A L per channel; a point luminaire's: its lumens x intensity per candela.
  Vec3 power() const { return isPoint() ? radiance * float(intensity->lumens()) : radiance * (kPi * area()); }
  Vec3 center() const {
    if (isPoint()) return corner;
    return isTriangle() ? corner + (edge1 + edge2) * (1.0f / 3.0f) : corner + (edge1 + edge2) * 0.5f;
  }
  // A point luminaire's frame: x its C0 direction, y C90 (counter-clockwise
  // from C0 seen from above, against the nadir), z its nadir.
  Vec3 luminaireC90() const { return cross(edge2, edge1); }
  Vec3 toLuminaire(const Vec3& direction) const {
    return Vec3(dot(direction, edge2), dot(direction, luminaireC90()), dot(direction, edge1));
  }
  Vec3 fromLuminaire(const Vec3& local) const { return edge2 * local.x + luminaireC90() * local.y + edge1 * local.z; }
  // A point luminaire's RGB intensity (W/sr) towards unit `direction`.
  Vec3 intensityToward(const Vec3& direction) const { return radiance * intensity->candela(toLuminaire(direction)); }
  // Whether a camera can see it: a point luminaire with a visible opening.
  bool seenAsOpening() const { return isPoint() && opening.visible(); }
  // Where the ray origin + t direction (unit) meets its opening, in (tMin, tMax).
  std::optional<float> openingHit(const Vec3& origin, const Vec3& direction, float tMin, float tMax) const {
    return opening.hit(toLuminaire(origin - corner), toLuminaire(direction), tMin, tMax);
  }
  // The RGB radiance its opening shows along a ray of unit `direction`
  // (towards it): I / A_projected of the light leaving it the other way.
  Vec3 openingRadiance(const Vec3& direction) const {
    const Vec3 out = toLuminaire(normalize(-direction));
    const double area = opening.projectedArea(out);
    if (!(area > 0)) return Vec3(0.0f);
    return radiance * float(double(intensity->candela(out)) / area);
  }
  // The world box around its opening (empty when it has none).
  Bounds3 openingBounds() const {
    Bounds3 box;
    if (!seenAsOpening()) return box;
    const Vec3 half = opening.size() * 0.5f;
    for (int k = 0; k < 8; ++k)
      box.extend(corner + fromLuminaire(Vec3(k & 1 ? half.x : -half.x, k & 2 ? half.y : -half.y,
                                             k & 4 ? half.z : -half.z)));
    return box;
  }
  // A uniformly distributed point for (u, v) uniform in [0,1)^2. A triangle
  // folds the square's far half onto itself (u + v > 1 -> 1 - u, 1 - v), so
  // both shapes use the same two random numbers.
  Vec3 pointAt(float u, float v) const {
    if (isPoint()) return corner;
    if (isTriangle() && u + v > 1.0f) {
      u = 1.0f - u;
      v = 1.0f - v;
    }
    return corner + edge1 * u + edge2 * v;
  }
  // Its 3 or 4 corners (a point luminaire: 1); returns how many were written.
  int corners(Vec3 (&out)[4]) const {
    out[0] = corner;
    if (isPoint()) return 1;
    out[1] = corner + edge1;
    out[2] = corner + edge2;
    out[3] = corner + edge1 + edge2;
    return isTriangle() ? 3 : 4;
  }
};

struct CellInfo {
  uint32_t id = 0;
  std::string name;
  Bounds3 bounds;
  uint64_t triangleCount = 0;
  uint64_t byteCount = 0;      // size of the cell file
  std::string file;            // relative to the store directory
};

// A planar convex polygon joining two cells.
struct Portal {
  uint32_t id = 0;
  uint32_t cellA = 0, cellB = 0;
  std::vector<Vec3> polygon;
};

// The name a store's default camera has when it is given none (and the one
// camera of a store written before cameras had names).
inline constexpr const char* kDefaultCameraName = "default";
// The longest camera name a store accepts (names are typed on command lines).
inline constexpr size_t kMaxCameraNameBytes = 128;

// A store camera. A store holds one or more, each with its own name; the
// first is its default camera.
struct Camera {
  std::string name = kDefaultCameraName;
  Vec3 origin, target, up{0, 1, 0};
  float fovYDegrees = 60.0f;   // full vertical field of view
  uint32_t width = 256, height = 256;
  uint32_t cell = 0;           // the cell containing origin
};

}  // namespace portico
