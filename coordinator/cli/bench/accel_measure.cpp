#include "coordinator/cli/bench/accel_measure.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <time.h>

#include "common/rng.h"
#include "common/transport/sampling.h"

namespace portico::cli {

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// CPU time of the calling thread: tracing is single-threaded (Embree's
// rtcIntersect1 runs on the caller too), and on a shared machine wall-clock
// passes swing by +-20 % with the load while the thread's own CPU time moves
// a few percent (only what other processes do to the shared caches remains).
double threadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

// CPU time of the whole process, every thread: a build's cost whatever
// threads it runs on (portico's build on the caller, Embree's on its pool),
// far steadier under load than the wall clock.
double processCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n == 0 ? 0.0 : (n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]));
}

std::vector<Ray> photonRays(const MeshView& mesh, size_t count, uint64_t seed) {
  std::vector<double> cumulativeArea(mesh.triangleCount);
  double total = 0;
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    total += 0.5 * double(length(mesh.geometricNormal(t)));
    cumulativeArea[t] = total;
  }
  std::vector<Ray> rays;
  rays.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    const auto u = [&](uint32_t dimension) { return randomUniform(seed, RandomStream::Photon, i, 0, dimension); };
    const double pick = double(u(0)) * total;
    const uint32_t primitive = uint32_t(std::min<size_t>(
        size_t(std::upper_bound(cumulativeArea.begin(), cumulativeArea.end(), pick) - cumulativeArea.begin()),
        mesh.triangleCount - 1));
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    const float r = std::sqrt(u(1)), s = u(2);
    const Vec3 point = v0 * (1 - r) + v1 * (r * (1 - s)) + v2 * (r * s);
    const Vec3 normal = normalize(mesh.geometricNormal(primitive));
    Vec3 tangent, bitangent;
    orthonormalBasis(normal, tangent, bitangent);
    const float radius = std::sqrt(u(3)), phi = 2 * kPi * u(4);
    const Vec3 direction = tangent * (radius * std::cos(phi)) + bitangent * (radius * std::sin(phi)) +
                           normal * std::sqrt(std::max(0.0f, 1 - radius * radius));
    // Off the surface as the renderer's bounced photons leave it.
    rays.push_back(Ray{offsetAlongNormal(point, normal), direction});
  }
  return rays;
}

std::vector<Ray> cameraRays(const FurnishedHall& hall, size_t count) {
  const Vec3 eye = hall.eye;
  const Vec3 across = normalize(hall.cell.bounds.hi - hall.cell.bounds.lo) * Vec3(1, 0, 1);
  const float pitch = -30.0f * kPi / 180.0f;
  const Vec3 forward = normalize(normalize(across) * std::cos(pitch) + Vec3(0, std::sin(pitch), 0));
  const Vec3 right = normalize(cross(forward, Vec3(0, 1, 0)));
  const Vec3 up = cross(right, forward);
  const float halfWidth = std::tan(50.0f * kPi / 180.0f);
  const size_t columns = std::max<size_t>(1, size_t(std::llround(std::sqrt(double(count) * 16.0 / 9.0))));
  const size_t rows = (count + columns - 1) / columns;
  const float halfHeight = halfWidth * float(rows) / float(columns);
  std::vector<Ray> rays;
  rays.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const float x = (2 * (float(i % columns) + 0.5f) / float(columns) - 1) * halfWidth;
    const float y = (1 - 2 * (float(i / columns) + 0.5f) / float(rows)) * halfHeight;
    rays.push_back(Ray{eye, normalize(forward + right * x + up * y)});
  }
  return rays;
}

std::vector<TraceResult> traceRaysInterleaved(const std::vector<const Accelerator*>& accelerators,
                                              const std::vector<Ray>& rays, uint32_t runs) {
  std::vector<TraceResult> results(accelerators.size());
  const auto trace = [&](size_t k, size_t count) {
    std::vector<Hit>& hits = results[k].hitList;
    for (size_t i = 0; i < count; ++i) hits[i] = accelerators[k]->intersect(rays[i]);
  };
  // Warm-up: caches, page faults, branch predictors.
  for (size_t k = 0; k < accelerators.size(); ++k) {
    results[k].hitList.resize(rays.size());
    trace(k, std::min<size_t>(rays.size(), 10000));
  }
  std::vector<std::vector<double>> seconds(accelerators.size());
  for (uint32_t run = 0; run < runs; ++run)
    for (size_t k = 0; k < accelerators.size(); ++k) {
      // The previous pass traced another structure: its data fills the caches.
      if (accelerators.size() > 1) trace(k, std::min<size_t>(rays.size(), 2000));
      const double start = threadCpuSeconds();
      trace(k, rays.size());
      seconds[k].push_back(threadCpuSeconds() - start);
    }
  for (size_t k = 0; k < accelerators.size(); ++k) {
    const double time = median(seconds[k]);
    results[k].mraysPerSecond = time > 0 ? double(rays.size()) / time * 1e-6 : 0.0;
    for (const Hit& hit : results[k].hitList) results[k].hits += hit.found();
  }
  return results;
}

TraceResult traceRays(const Accelerator& accelerator, const std::vector<Ray>& rays, uint32_t runs) {
  return std::move(traceRaysInterleaved({&accelerator}, rays, runs).front());
}

std::unique_ptr<Accelerator> timedBuild(const AcceleratorSpec& spec, const MeshView& mesh, uint32_t runs,
                                        double& medianMs) {
  std::unique_ptr<Accelerator> accelerator;
  std::vector<double> milliseconds;
  for (uint32_t run = 0; run < runs; ++run) {
    accelerator.reset();  // free the previous one first: measure one structure's memory at a time
    const double start = processCpuSeconds();
    accelerator = buildAccelerator(spec, mesh);
    milliseconds.push_back((processCpuSeconds() - start) * 1e3);
    if (milliseconds.back() > 20000) break;
  }
  medianMs = median(milliseconds);
  return accelerator;
}

// "1000,10k,1M" -> {1000, 10000, 1000000}.
std::vector<size_t> parseTriangleCounts(const std::string& text) {
  std::vector<size_t> sizes;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    double scale = 1;
    const std::string suffix = end ? std::string(end) : "";
    if (suffix == "k" || suffix == "K") scale = 1e3;
    else if (suffix == "m" || suffix == "M") scale = 1e6;
    else if (!suffix.empty()) scale = 0;
    if (item.empty() || end == item.c_str() || scale == 0 || !(value * scale >= 12) || value * scale > 4e9)
      throw std::invalid_argument("--sizes: '" + item +
                                  "' is not a triangle count from 12 to 4e9 (write e.g. 1000,10k,1M)");
    sizes.push_back(size_t(std::llround(value * scale)));
    start = comma + 1;
  }
  return sizes;
}

MeshView hallMesh(FurnishedHall& hall) {
  // One readable float after the last vertex, as a cell file can promise:
  // Embree may share the vertices.
  const size_t vertexCount = hall.cell.positions.size() / 3;
  hall.cell.positions.push_back(0.0f);
  MeshView mesh;
  mesh.positions = hall.cell.positions.data();
  mesh.vertexCount = vertexCount;
  mesh.indices = hall.cell.indices.data();
  mesh.triangleCount = hall.cell.indices.size() / 3;
  mesh.positionsPaddingFloats = 1;
  return mesh;
}

}  // namespace portico::cli
