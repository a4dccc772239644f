// portico-fuzz-seeds OUT STORE: the fuzzers' seed corpus. Real messages,
// built with the wire types the programs use (one per Envelope variant), a
// real cell file and catalogue from STORE (a `portico scene generate` store).
#include <capnp/dynamic.h>
#include <capnp/message.h>
#include <fmt/format.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>

#include "common/net/message.h"
#include "common/transport/photon_record.h"
#include "common/net/ray_wire.h"
#include "tests/fuzz/fuzz_support.h"

using namespace portico;
namespace fs = std::filesystem;

namespace {

void write(const fs::path& path, const void* data, size_t size) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
}

void writeEnvelope(const fs::path& dir, const std::string& name, capnp::MallocMessageBuilder& message) {
  const zmq::message_t frame = net::encode(message);
  write(dir / (name + ".bin"), frame.data(), frame.size());
}

std::vector<RayState> sampleRays(RayKind kind, size_t count) {
  std::vector<RayState> rays(count);
  for (size_t i = 0; i < count; ++i) {
    RayState& ray = rays[i];
    ray.kind = kind;
    ray.depth = static_cast<uint16_t>(i % 4);
    ray.pathId = 1000 + i;
    ray.pixel = static_cast<uint32_t>(i * 7);
    ray.origin = Vec3(1.0f + 0.1f * float(i), 1.2f, 0.5f);
    ray.direction = normalize(Vec3(0.3f, -0.2f + 0.05f * float(i), 0.9f));
    ray.tMin = 1e-4f;
    ray.tMax = kind == RayKind::Shadow ? 3.5f : kInfinity;
    ray.weight = Vec3(0.8f, 0.7f, 0.6f);
  }
  return rays;
}

void fillRays(capnp::List<wire::Ray>::Builder list, const std::vector<RayState>& rays) {
  for (size_t i = 0; i < rays.size(); ++i) toWire(rays[i], list[static_cast<unsigned>(i)]);
}

std::string sampleRecords(size_t count) {
  std::vector<StoredPhoton> photons(count);
  for (size_t i = 0; i < count; ++i) {
    photons[i].position = Vec3(0.5f * float(i), 0.0f, 1.0f + 0.25f * float(i % 3));
    photons[i].direction = normalize(Vec3(0.1f, -1.0f, 0.2f * float(i % 2)));
    photons[i].power = Vec3(0.01f, 0.012f, 0.009f);
    photons[i].bounce = static_cast<uint16_t>(i % 3);
  }
  return packRecords(photons, fuzz::photonFrame());
}

capnp::Data::Reader asData(const std::string& bytes) {
  return capnp::Data::Reader(reinterpret_cast<const kj::byte*>(bytes.data()), bytes.size());
}

void fillSpec(wire::JobSpec::Builder spec, const std::string& store) {
  spec.setStore(store);
  spec.setOutput("/tmp/out.png");
  spec.setPhotons(200000);
  spec.setSpp(16);
  spec.setSeed(1);
  spec.setAccel("grid");
  spec.setWidth(96);
  spec.setHeight(64);
  spec.setExposure(1);
  spec.setLightSamples(2);
  spec.setPhotonK(64);
  spec.setPhotonRadius(0.5f);
  spec.setGather(8);
}

// One seed per Envelope variant: real content for the ones portico's
// programs exchange most, default content for the rest (found by reflection,
// so a variant added later gets a seed too).
void envelopeSeeds(const fs::path& dir, const std::string& store) {
  std::set<std::string> written;
  const auto put = [&](const std::string& name, capnp::MallocMessageBuilder& message) {
    writeEnvelope(dir, name, message);
    written.insert(name);
  };
  {
    capnp::MallocMessageBuilder m;
    auto hello = m.initRoot<wire::Envelope>().initHello();
    hello.setVersion(wire::PROTOCOL_VERSION);
    hello.setName("seed-worker:1234");
    hello.setCores(2);
    hello.setMemoryBytes(uint64_t(2) << 30);
    put("hello", m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto welcome = m.initRoot<wire::Envelope>().initWelcome();
    welcome.setVersion(wire::PROTOCOL_VERSION);
    welcome.setHeartbeatMs(1000);
    welcome.setMaxFrameBytes(net::maxCoordinatorFrameBytes(50000));
    put("welcome", m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto assign = m.initRoot<wire::Envelope>().initAssign();
    assign.setLease(7);
    assign.setAttempt(1);
    assign.setJob(1);
    assign.setPhase(wire::Phase::RENDER);
    assign.setCell(0);
    fillSpec(assign.initSpec(), store);
    auto batches = assign.initBatches(3);
    auto emit = batches[0].initEmit();
    emit.setLight(0);
    emit.setFirstPath(20000);
    emit.setCount(20000);
    emit.setPhotonsOfLight(100000);
    batches[1].initCamera().setPixelCount(1024);
    const auto rays = sampleRays(RayKind::Gather, 6);
    fillRays(batches[2].initRays(static_cast<unsigned>(rays.size())), rays);
    put("assign", m);
  }
  {
    // A photon-pass lease of several cells (protocol 4).
    capnp::MallocMessageBuilder m;
    auto assign = m.initRoot<wire::Envelope>().initAssign();
    assign.setLease(8);
    assign.setAttempt(1);
    assign.setJob(1);
    assign.setPhase(wire::Phase::PHOTONS);
    assign.setCell(0);
    fillSpec(assign.initSpec(), store);
    const auto rays = sampleRays(RayKind::Photon, 3);
    fillRays(assign.initBatches(1)[0].initRays(static_cast<unsigned>(rays.size())), rays);
    auto more = assign.initMoreCells(2);
    for (unsigned c = 0; c < 2; ++c) {
      more[c].setCell(c + 1);
      fillRays(more[c].initBatches(1)[0].initRays(static_cast<unsigned>(rays.size())), rays);
    }
    put("assign_more_cells", m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto result = m.initRoot<wire::Envelope>().initResult();
    result.setLease(7);
    auto counters = result.initCounters(2);
    counters[0].setName("photons.deposits");
    counters[0].setValue(12);
    counters[1].setName("rays.crossings");
    counters[1].setValue(5);
    auto crossings = result.initCrossings(2);
    for (unsigned c = 0; c < 2; ++c) {
      crossings[c].setCell(c + 1);
      const auto rays = sampleRays(c ? RayKind::Shadow : RayKind::Photon, 4);
      fillRays(crossings[c].initRays(static_cast<unsigned>(rays.size())), rays);
    }
    auto deposits = result.initDeposits(2);
    const std::string records = sampleRecords(6);
    for (unsigned d = 0; d < 2; ++d) {
      deposits[d].setCell(d);
      deposits[d].setRecords(asData(records));
    }
    auto film = result.initFilm(4);
    for (unsigned p = 0; p < 4; ++p) {
      film[p].setPixel(p * 3);
      film[p].setR(1 << 20);
      film[p].setG(3 << 18);
      film[p].setB(5 << 16);
    }
    put("result", m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto failure = m.initRoot<wire::Envelope>().initFailure();
    failure.setLease(7);
    failure.setMessage("cell file /store/cells/5.cell: malformed message");
    put("failure", m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto photons = m.initRoot<wire::Envelope>().initPhotons();
    photons.setJob(1);
    photons.setCell(0);
    auto batches = photons.initBatches(2);
    batches.set(0, asData(sampleRecords(5)));
    batches.set(1, asData(sampleRecords(9)));
    put("photons", m);
  }
  {
    capnp::MallocMessageBuilder m;
    fillSpec(m.initRoot<wire::Envelope>().initSubmit().initSpec(), store);
    put("submit", m);
  }
  {
    capnp::MallocMessageBuilder m;
    m.initRoot<wire::Envelope>().initStatusReply().setJson(R"({"job":1,"state":"render","workers":[]})");
    put("statusReply", m);
  }
  {
    capnp::MallocMessageBuilder m;
    m.initRoot<wire::Envelope>().setError("job 999 does not exist");
    put("error", m);
  }
  // Every other variant, through reflection.
  const capnp::StructSchema schema = capnp::Schema::from<wire::Envelope>();
  for (const capnp::StructSchema::Field field : schema.getUnionFields()) {
    const std::string name = field.getProto().getName();
    if (written.count(name)) continue;
    capnp::MallocMessageBuilder m;
    auto envelope = capnp::toDynamic(m.initRoot<wire::Envelope>());
    switch (field.getType().which()) {
      case capnp::schema::Type::STRUCT: {
        auto body = envelope.init(field).as<capnp::DynamicStruct>();
        for (const auto member : body.getSchema().getNonUnionFields()) {
          const auto type = member.getType().which();
          if (type == capnp::schema::Type::UINT64 || type == capnp::schema::Type::UINT32)
            body.set(member, 1);
          else if (type == capnp::schema::Type::TEXT)
            body.set(member, capnp::Text::Reader("cells/0.cell"));
        }
        break;
      }
      case capnp::schema::Type::TEXT: envelope.set(field, capnp::Text::Reader("x")); break;
      default: envelope.set(field, capnp::VOID);
    }
    writeEnvelope(dir, name, m);
  }
}

void rayBatchSeeds(const fs::path& dir, const std::string& store) {
  const auto putPacked = [&](const std::string& name, uint8_t selector, capnp::MallocMessageBuilder& m) {
    const std::string packed = std::string(1, char(selector)) + net::packToString(m);
    write(dir / (name + ".bin"), packed.data(), packed.size());
  };
  {
    capnp::MallocMessageBuilder m;
    const auto rays = sampleRays(RayKind::Camera, 8);
    fillRays(m.initRoot<wire::RayBatch>().initRays(static_cast<unsigned>(rays.size())), rays);
    putPacked("rays", 0, m);
    const std::string flat = std::string(1, char(2)) + net::flatToString(m);   // as onResult stores crossings
    write(dir / "rays-flat.bin", flat.data(), flat.size());
  }
  {
    capnp::MallocMessageBuilder m;
    auto emit = m.initRoot<wire::RayBatch>().initEmit();
    emit.setLight(1);
    emit.setCount(20000);
    emit.setPhotonsOfLight(40000);
    putPacked("emit", 0, m);
  }
  {
    capnp::MallocMessageBuilder m;
    auto camera = m.initRoot<wire::RayBatch>().initCamera();
    camera.setFirstPixel(4096);
    camera.setPixelCount(1024);
    putPacked("camera", 0, m);
  }
  {
    capnp::MallocMessageBuilder m;
    fillSpec(m.initRoot<wire::JobSpec>(), store);
    putPacked("spec", 1, m);
  }
}

// The catalogue with 512-byte pages: the same tables in a fraction of the
// bytes, so mutations reach them more often.
void compactCatalogue(const fs::path& path) {
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK ||
      sqlite3_exec(db, "PRAGMA journal_mode=DELETE; PRAGMA page_size=512; VACUUM;", nullptr, nullptr, nullptr) !=
          SQLITE_OK)
    throw std::runtime_error(fmt::format("cannot compact {}: {}", path.string(), sqlite3_errmsg(db)));
  sqlite3_close(db);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: portico-fuzz-seeds OUT STORE   (STORE: from `portico scene generate --preset demo`)\n";
    return 2;
  }
  try {
    const fs::path out(argv[1]), store = fs::absolute(argv[2]);
    envelopeSeeds(out / "envelope", store.string());
    rayBatchSeeds(out / "ray_batch", store.string());
    const std::string records = sampleRecords(12);
    write(out / "photon_records" / "records.bin", records.data(), records.size());
    fs::create_directories(out / "cell_file");
    fs::copy_file(store / "cells" / "0.cell", out / "cell_file" / "0.cell", fs::copy_options::overwrite_existing);
    fs::create_directories(out / "scene_db");
    fs::copy_file(store / "scene.db", out / "scene_db" / "scene.db", fs::copy_options::overwrite_existing);
    compactCatalogue(out / "scene_db" / "scene.db");
    std::cout << fmt::format("seeds written to {}\n", out.string());
  } catch (const std::exception& e) {
    std::cerr << "portico-fuzz-seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
