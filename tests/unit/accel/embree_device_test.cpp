#include "common/accel/embree_device.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace portico {
namespace {

// One triangle in the plane z = `z`, over x, y in [0, 1]; a float of padding after its vertices.
struct Triangle {
  explicit Triangle(float z) : positions{0, 0, z, 1, 0, z, 0, 1, z, 0} {}
  MeshView mesh(size_t padding) const { return {positions.data(), 3, indices.data(), 1, padding}; }
  std::vector<float> positions;
  std::vector<uint32_t> indices{0, 1, 2};
};

unsigned hitGeometry(RTCScene scene, float z) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(16) RTCRayHit query{};
  query.ray.org_x = 0.2f, query.ray.org_y = 0.2f, query.ray.org_z = z;
  query.ray.dir_z = -1.0f;
  query.ray.tfar = 100.0f;
  query.ray.mask = 0xffffffffu;
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &query);
  return query.hit.geomID;
}

TEST(EmbreeDevice, AttachesMeshesUnderTheirIdsSharingOrCopyingTheVertices) {
  EmbreeDevice device("threads=1");
  EXPECT_EQ(device.config(), "threads=1");
  EmbreeDevice::clearErrors();
  RTCScene scene = rtcNewScene(device.handle());
  const Triangle low(0.0f), high(1.0f), empty(2.0f);
  std::vector<float> lowCopy, highCopy, emptyCopy;
  attachEmbreeTriangles(device, scene, low.mesh(0), RTC_BUILD_QUALITY_MEDIUM, lowCopy, 5);   // no padding: copied
  attachEmbreeTriangles(device, scene, high.mesh(1), RTC_BUILD_QUALITY_MEDIUM, highCopy, 2);  // shared
  attachEmbreeTriangles(device, scene, MeshView{}, RTC_BUILD_QUALITY_MEDIUM, emptyCopy, 9);   // nothing
  rtcCommitScene(scene);
  EXPECT_NO_THROW(EmbreeDevice::check("building"));
  EXPECT_EQ(lowCopy, std::vector<float>({0, 0, 0, 1, 0, 0, 0, 1, 0, 0}));
  EXPECT_TRUE(highCopy.empty());
  EXPECT_TRUE(emptyCopy.empty());
  EXPECT_GT(device.bytesAllocated(), 0);
  EXPECT_EQ(hitGeometry(scene, 3.0f), 2u);   // the higher triangle first
  EXPECT_EQ(hitGeometry(scene, 0.5f), 5u);
  EXPECT_EQ(hitGeometry(scene, -0.5f), RTC_INVALID_GEOMETRY_ID);
  rtcReleaseScene(scene);
}

TEST(EmbreeDevice, EmbreesErrorsOnThisThreadBecomeAnException) {
  EmbreeDevice device("");
  EmbreeDevice::clearErrors();
  RTCScene scene = rtcNewScene(device.handle());
  const Triangle triangle(0.0f);
  std::vector<float> copy;
  attachEmbreeTriangles(device, scene, triangle.mesh(1), RTC_BUILD_QUALITY_LOW, copy, 4);
  EXPECT_NO_THROW(EmbreeDevice::check("first"));
  attachEmbreeTriangles(device, scene, triangle.mesh(1), RTC_BUILD_QUALITY_LOW, copy, 4);   // id 4 is taken
  try {
    EmbreeDevice::check("adding cell 4");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("embree: adding cell 4 (Embree error ", 0), 0u) << e.what();
  }
  EXPECT_NO_THROW(EmbreeDevice::check("after"));   // reported once
  rtcReleaseScene(scene);
}

}  // namespace
}  // namespace portico
