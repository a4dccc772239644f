#include "coordinator/cli/scene_export_radiance.h"

#include <fmt/format.h>
#include <fmt/os.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "common/job/sun_time.h"
#include "common/photometry/lamp_colour.h"
#include "common/scene/import/quad_light.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/sky_model.h"
#include "common/transport/sun_disc.h"
#include "coordinator/cli/export_groups.h"

namespace portico::cli {

namespace {

namespace fs = std::filesystem;
constexpr double kWhiteEfficacy = 179.0;            // lm/W (docs/daylight.md)
constexpr double kOvercastHorizontalLux = 10000.0;  // portico's --sky overcast
constexpr double kGroundAlbedo = 0.2;               // below the horizon of the overcast sky

std::string materialName(const Material& m) { return fmt::format("m{}", m.id); }

// Radiance identifiers are words: a cell's name with anything but letters,
// digits and _.- turned into _.
std::string identifier(const std::string& name) {
  std::string word = name.empty() ? "cell" : name;
  for (char& c : word)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '.' && c != '-') c = '_';
  return word;
}

// Writes a file under a temporary name and renames it when complete, so a
// failed export leaves nothing half-written.
class AtomicTextFile {
 public:
  explicit AtomicTextFile(std::string path) : path_(std::move(path)), temporary_(path_ + ".partial") {}
  ~AtomicTextFile() {
    if (!committed_) {
      out_.reset();
      std::error_code ignored;
      fs::remove(temporary_, ignored);
    }
  }
  fmt::ostream& out() {
    if (!out_) out_ = std::make_unique<fmt::ostream>(fmt::output_file(temporary_));
    return *out_;
  }
  void commit() {
    out().close();
    fs::rename(temporary_, path_);
    committed_ = true;
  }

 private:
  std::string path_, temporary_;
  std::unique_ptr<fmt::ostream> out_;
  bool committed_ = false;
};

// Returns how many material definitions were written.
uint32_t writeMaterials(const SceneStore& store, fmt::ostream& out) {
  for (const Material& m : store.materials()) {
    out.print("\n# {}{}\n", m.name, m.textured() ? " (albedo texture not exported: its albedo factor only)" : "");
    if (m.glass()) {
      out.print("void glass {}\n0\n0\n4 {} {} {} {}\n", materialName(m),
                radianceGlassTransmissivity(m.transmittance.x, m.ior),
                radianceGlassTransmissivity(m.transmittance.y, m.ior),
                radianceGlassTransmissivity(m.transmittance.z, m.ior), m.ior);
    } else if (m.emissive()) {
      out.print("void light {}\n0\n0\n3 {} {} {}\n", materialName(m), m.emission.x, m.emission.y, m.emission.z);
    } else {
      out.print("void plastic {}\n0\n0\n5 {} {} {} 0 0\n", materialName(m), m.albedo.x, m.albedo.y, m.albedo.z);
    }
  }
  return static_cast<uint32_t>(store.materials().size());
}

void writePolygon(fmt::ostream& out, const std::string& modifier, const std::string& name, const Vec3* v, int count,
                  ExportSummary& summary) {
  out.print("{} polygon {}\n0\n0\n{}", modifier, name, 3 * count);
  for (int i = 0; i < count; ++i) {
    out.print("\n  {} {} {}", v[i].x, v[i].y, v[i].z);
    summary.bounds.extend(v[i]);
  }
  out.print("\n");
  ++summary.polygons;
}

// The corners of a lamp of two triangles in the order Radiance wants them:
// anticlockwise seen from the side it emits to (cross(edge1, edge2)).
bool lampQuad(const MeshView& mesh, const TriangleGroup& lamp, Vec3 (&quad)[4]) {
  if (lamp.triangles.size() != 2) return false;
  std::vector<float> positions;
  for (uint32_t t : lamp.triangles) {
    Vec3 v[3];
    mesh.triangle(t, v[0], v[1], v[2]);
    for (const Vec3& p : v) positions.insert(positions.end(), {p.x, p.y, p.z});
  }
  std::string problem;
  const auto p = parallelogramFromTriangles(positions, {0, 1, 2, 3, 4, 5}, problem);
  if (!p) return false;
  quad[0] = p->corner;
  quad[1] = p->corner + p->edge1;
  quad[2] = p->corner + p->edge1 + p->edge2;
  quad[3] = p->corner + p->edge2;
  return true;
}

void writeGeometry(const SceneStore& store, fmt::ostream& out, ExportSummary& summary) {
  for (const CellInfo& cell : store.cells()) {
    const std::unique_ptr<CellGeometry> geometry =
        CellGeometry::load(store.cellPath(cell.id), cell.id, store.materials().size());
    const MeshView& mesh = geometry->mesh();
    const std::string cellName = identifier(cell.name);
    out.print("\n# cell {} ({} triangles)\n", cell.name, mesh.triangleCount);
    uint32_t lamp = 0;
    for (const TriangleGroup& group : exportGroups(*geometry, store.materials())) {
      const std::string modifier = materialName(store.materials()[group.material]);
      summary.triangles += group.triangles.size();
      Vec3 quad[4];
      if (group.lamp && lampQuad(mesh, group, quad)) {
        writePolygon(out, modifier, fmt::format("{}.lamp{}", cellName, lamp++), quad, 4, summary);
        continue;
      }
      for (uint32_t t : group.triangles) {
        Vec3 v[3];
        mesh.triangle(t, v[0], v[1], v[2]);
        const std::string name =
            group.lamp ? fmt::format("{}.lamp{}", cellName, lamp++) : fmt::format("{}.t{}", cellName, t);
        writePolygon(out, modifier, name, v, 3, summary);
      }
    }
  }
}

// Each store camera as the rpict view options that show what it shows.
void writeViews(const SceneStore& store, fmt::ostream& out) {
  for (const Camera& c : store.cameras()) {
    const Vec3 d = normalize(c.target - c.origin);
    const double halfY = c.fovYDegrees * kPi / 360.0;
    const double fovX = 2.0 * std::atan(double(c.width) / c.height * std::tan(halfY)) * 180.0 / kPi;
    out.print("# view {}: rpict -vtv -vp {} {} {} -vd {} {} {} -vu {} {} {} -vv {} -vh {} -x {} -y {}\n", c.name,
              c.origin.x, c.origin.y, c.origin.z, d.x, d.y, d.z, c.up.x, c.up.y, c.up.z, c.fovYDegrees, fovX, c.width,
              c.height);
  }
}

void writeGlowSource(fmt::ostream& out, const std::string& modifier, const Vec3& radiance, const std::string& glow,
                     const std::string& source, double upSign) {
  out.print("{} glow {}\n0\n0\n4 {} {} {} 0\n", modifier, glow, radiance.x, radiance.y, radiance.z);
  out.print("{} source {}\n0\n0\n4 0 {} 0 180\n", glow, source, upSign);
}

// The sky and the sun of `daylight` (already checked, its sun time resolved).
void writeSky(const DaylightSettings& daylight, const std::string& storeDirectory, fmt::ostream& out) {
  using Sky = DaylightSettings::Sky;
  out.print("# Daylight of scene store {} as portico's --sky/--sun give it, in portico's coordinates (+Y up).\n",
            storeDirectory);
  Vec3 sunOnGround;   // the sun's irradiance on the ground, W/m^2 per channel
  if (daylight.sun) {
    const Vec3 direction = sunDirection(daylight.sunAzimuthDegrees, daylight.sunElevationDegrees);
    const Vec3 irradiance = maxComponent(daylight.sunIrradiance) > 0
                                ? daylight.sunIrradiance
                                : modelledSunIrradiance(daylight.sunElevationDegrees, daylight.turbidity);
    sunOnGround = irradiance * direction.y;
    // Radiance's source of angle a covers 2 pi (1 - cos(a/2)): portico's disc.
    const Vec3 radiance = irradiance / kSunDiscSolidAngle;
    out.print("\n# the sun: --sun {},{}, irradiance {} {} {} W/m^2 facing it, a disc 0.53 degrees across\n",
              daylight.sunAzimuthDegrees, daylight.sunElevationDegrees, irradiance.x, irradiance.y, irradiance.z);
    out.print("void light solar\n0\n0\n3 {} {} {}\n", radiance.x, radiance.y, radiance.z);
    out.print("solar source sun\n0\n0\n4 {} {} {} 0.53\n", direction.x, direction.y, direction.z);
  }
  if (daylight.sky == Sky::Overcast) {
    const double horizontal = kOvercastHorizontalLux / kWhiteEfficacy;
    const double zenith = horizontal / (kPi * 7.0 / 9.0);   // E = Lz 7 pi / 9 for L = Lz (1 + 2 cos) / 3
    const Vec3 ground = (Vec3(float(horizontal)) + sunOnGround) * float(kGroundAlbedo / kPi);
    out.print(
        "\n# --sky overcast: the CIE overcast sky, {} lx on an unobstructed horizontal plane (what\n"
        "# `gensky -ang 45 0 -c -B {:.4f} -g {} | xform -rx -90` writes), and below the horizon portico's ground:\n"
        "# albedo {}, lit by the sky and the sun if any.\n",
        kOvercastHorizontalLux, horizontal, kGroundAlbedo, kGroundAlbedo);
    out.print("void brightfunc skyfunc\n4 skybr skybright.cal -rx -90\n0\n3 2 {} {}\n", zenith,
              kGroundAlbedo * horizontal / kPi);
    writeGlowSource(out, "skyfunc", Vec3(1), "sky_glow", "sky", 1);
    writeGlowSource(out, "void", ground, "ground_glow", "ground", -1);
  } else if (daylight.sky == Sky::Uniform) {
    out.print("\n# --sky uniform:{},{},{}: this radiance from every direction, below the horizon too\n",
              daylight.skyRadiance.x, daylight.skyRadiance.y, daylight.skyRadiance.z);
    writeGlowSource(out, "void", daylight.skyRadiance, "sky_glow", "sky", 1);
    out.print("sky_glow source ground\n0\n0\n4 0 -1 0 180\n");
  }
}

// A point luminaire as Radiance sources are made from IES files (as
// ies2rad makes them): a `light` sphere whose radiance a `brightdata`
// pattern scales by the luminaire's candela towards each direction, read
// from a data file beside the scene in source.cal's coordinates: theta
// from the nadir (its -z), phi from C0 (its +x) towards C90 (its +y). A
// sphere of radius r shows a projected area of pi r^2 every way, so a
// radiance of intensity / (pi r^2) gives the intensity.
constexpr double kLuminaireRadius = 0.005;   // metres: well inside the 1 cm a point keeps from a ceiling
constexpr int kThetaSteps = 180;             // 1 degree
constexpr int kPhiSteps = 180;               // 2 degrees

// Euler angles (degrees) of xform's `-rx a -ry b -rz c`, which turn the
// pattern's frame (x C0, y C90, z up: against the nadir) into the scene's.
Vec3 luminaireRotation(const AreaLight& light) {
  const Vec3 x = light.edge2, y = light.luminaireC90(), z = -light.edge1;   // the columns of M
  const double m00 = x.x, m10 = x.y, m20 = x.z, m21 = y.z, m22 = z.z, m11 = y.y, m12 = z.y;
  const double cosB = std::hypot(m00, m10);
  double a, b = std::atan2(-m20, cosB), c;
  if (cosB > 1e-6) {
    a = std::atan2(m21, m22);
    c = std::atan2(m10, m00);
  } else {   // looking straight along x: M = Ry(b) Rx(a)
    a = std::atan2(-m12, m11);
    c = 0;
  }
  return Vec3(float(a * 180 / kPi), float(b * 180 / kPi), float(c * 180 / kPi));
}

// The data file: phi (slowest) by theta, candela.
void writeLuminaireData(const AreaLight& light, const std::string& path) {
  AtomicTextFile data(path);
  fmt::ostream& out = data.out();
  out.print("2\n0 360 {}\n0 180 {}\n", kPhiSteps + 1, kThetaSteps + 1);
  for (int p = 0; p <= kPhiSteps; ++p) {
    const double phi = 2 * kPi * p / kPhiSteps;
    for (int t = 0; t <= kThetaSteps; ++t) {
      const double theta = kPi * t / kThetaSteps;
      const Vec3 local(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                       float(std::cos(theta)));
      out.print("{:.6g}{}", light.intensity->candela(local), t == kThetaSteps ? "\n" : " ");
    }
  }
  data.commit();
}

// Writes each point luminaire's source into `out` and its data file beside
// `radPath`; returns how many.
uint32_t writeLuminaires(const SceneStore& store, const std::string& radPath, fmt::ostream& out) {
  uint32_t written = 0;
  for (const AreaLight& light : store.lights()) {
    if (!light.isPoint()) continue;
    const fs::path data = fs::path(radPath).replace_extension(fmt::format(".luminaire{}.dat", light.id));
    writeLuminaireData(light, data.string());
    const Vec3 r = luminaireRotation(light);
    const Vec3 radiance = light.radiance * float(1.0 / (kPi * kLuminaireRadius * kLuminaireRadius));
    const std::string name = fmt::format("luminaire{}", light.id);
    out.print("# point luminaire {} ({}, {:.1f} lm): nadir {} {} {}, C0 {} {} {}; candela in {}\n", light.id,
              light.intensity->name(), lumensOfPower(light.power()), light.edge1.x, light.edge1.y, light.edge1.z,
              light.edge2.x, light.edge2.y, light.edge2.z, data.filename().string());
    out.print("void brightdata {0}_dist\n11 noop {1} source.cal src_phi src_theta -rx {2} -ry {3} -rz {4}\n0\n0\n"
              "{0}_dist light {0}_light\n0\n0\n3 {5} {6} {7}\n"
              "{0}_light sphere {0}\n0\n0\n4 {8} {9} {10} {11}\n",
              name, data.filename().string(), r.x, r.y, r.z, radiance.x, radiance.y, radiance.z, light.corner.x,
              light.corner.y, light.corner.z, kLuminaireRadius);
    ++written;
  }
  return written;
}

}  // namespace

bool isRadiancePath(const std::string& path) { return fs::path(path).extension() == ".rad"; }

std::string radianceSkyPath(const std::string& radPath) {
  return fs::path(radPath).replace_extension(".sky.rad").string();
}

double radianceGlassTransmissivity(double tint, double ior) {
  if (!(tint > 0)) return 0;
  const double r = (ior - 1) * (ior - 1) / ((ior + 1) * (ior + 1));
  const double transmittance = tint * (1 - r) / (1 + r);   // thin_glass.h at normal incidence
  const double a = r * r * transmittance, b = (1 - r) * (1 - r);
  // a tn^2 + b tn - T = 0, the positive root.
  return (std::sqrt(b * b + 4 * a * transmittance) - b) / (2 * a);
}

ExportSummary exportStoreRadiance(const std::string& directory, const std::string& radPath,
                                  const DaylightSettings& requested) {
  using Sky = DaylightSettings::Sky;
  if (!isRadiancePath(radPath))
    throw std::runtime_error(fmt::format("{}: a Radiance export is written to FILE.rad", radPath));
  const SceneStore store = SceneStore::open(directory);
  const DaylightSettings daylight = resolveSunTime(requested, store.site(), store.directory());
  if (const std::string problem = daylightProblem(daylight); !problem.empty()) throw std::runtime_error(problem);
  if (daylight.sky == Sky::Preetham)
    throw std::runtime_error(
        "--sky preetham (also what --sun alone brings): Radiance has no Preetham sky; export the sun with --sky "
        "overcast or --sky uniform:R,G,B");

  const std::string skyPath = radianceSkyPath(radPath);
  const std::string skyFile = fs::path(skyPath).filename().string();
  ExportSummary summary;
  AtomicTextFile scene(radPath);
  fmt::ostream& out = scene.out();
  out.print("# Radiance scene of portico scene store {}: {} cells, {} portals, {} materials.\n", store.directory(),
            store.cells().size(), store.portals().size(), store.materials().size());
  out.print(
      "# Metres, portico's coordinates (+Y up). Radiance per RGB channel in W m^-2 sr^-1, as portico's:\n"
      "# illuminance in lux = 179 x Y of rtrace -I's irradiance (portico: Rec. 709 Y; Radiance: 0.265 0.670 0.065).\n");
  if (daylight.any())
    out.print("# Daylight in {}: oconv {} {} > scene.oct\n", skyFile, skyFile, fs::path(radPath).filename().string());
  else
    out.print(
        "# No daylight: `portico scene export STORE -o FILE.rad --sky overcast` (or uniform:R,G,B, --sun) writes\n"
        "# the sky as FILE.sky.rad (the CIE overcast sky is gensky -c -B 55.866 turned to +Y up).\n");
  out.print("# Illuminance at sensors: rtrace -h -I -ab 8 -lr -16 -ad 4096 -aa 0 -lw 1e-5 scene.oct < sensors.pts\n");
  writeViews(store, out);
  for (const Portal& p : store.portals()) {
    out.print("# portal {} {}", store.cells()[p.cellA].name, store.cells()[p.cellB].name);
    for (const Vec3& v : p.polygon) out.print(" {} {} {}", v.x, v.y, v.z);
    out.print("\n");
  }
  summary.materials = writeMaterials(store, out);
  writeGeometry(store, out, summary);
  summary.luminaires = writeLuminaires(store, radPath, out);
  if (daylight.any()) {
    AtomicTextFile sky(skyPath);
    writeSky(daylight, store.directory(), sky.out());
    sky.commit();
    summary.skyFile = skyPath;
  }
  scene.commit();
  return summary;
}

}  // namespace portico::cli
