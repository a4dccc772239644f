#include "coordinator/analysis_sensors.h"

#include <capnp/message.h>
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>

#include "common/net/message.h"

namespace portico {

namespace {
// One sensor as jobs.db keeps it.
struct SensorRecord {
  float position[3];
  float direction[3];
  uint32_t line;
  int32_t cell;
};
static_assert(sizeof(SensorRecord) == 32);

std::string nameOf(const Sensor& sensor, size_t index) {
  return sensor.sourceLine ? fmt::format("sensor {} (line {})", index, sensor.sourceLine)
                           : fmt::format("sensor {}", index);
}
}  // namespace

std::vector<Sensor> sensorsOfSubmit(capnp::List<wire::SensorPoint>::Reader points, const SceneStore& scene) {
  std::vector<Sensor> sensors;
  sensors.reserve(points.size());
  size_t inCells = 0;
  for (auto point : points) {
    Sensor sensor;
    sensor.position = Vec3(point.getX(), point.getY(), point.getZ());
    sensor.direction = Vec3(point.getDx(), point.getDy(), point.getDz());
    sensor.sourceLine = point.getLine();
    const std::string name = nameOf(sensor, sensors.size());
    if (point.getIndex() != sensors.size())
      throw std::invalid_argument(fmt::format("{}: its index is {}", name, point.getIndex()));
    if (!isFinite(sensor.position) || !isFinite(sensor.direction))
      throw std::invalid_argument(fmt::format("{}: not a finite point and direction", name));
    const float length = portico::length(sensor.direction);
    if (!(length > 1e-6f) || !std::isfinite(length)) throw std::invalid_argument(fmt::format("{}: its direction is zero", name));
    sensor.direction = sensor.direction / length;
    if (const auto cell = scene.locateCell(sensor.position)) {
      sensor.cell = *cell;
      sensor.room = scene.cells()[*cell].name;
      ++inCells;
    }
    sensors.push_back(std::move(sensor));
  }
  if (inCells == 0)
    throw std::invalid_argument(fmt::format("none of the {} sensors lies inside a cell of scene {}", sensors.size(),
                                            scene.directory()));
  return sensors;
}

std::string encodeSensors(const std::vector<Sensor>& sensors) {
  std::string records(sensors.size() * sizeof(SensorRecord), '\0');
  for (size_t i = 0; i < sensors.size(); ++i) {
    const Sensor& s = sensors[i];
    const SensorRecord record{{s.position.x, s.position.y, s.position.z},
                              {s.direction.x, s.direction.y, s.direction.z},
                              s.sourceLine,
                              int32_t(s.cell)};
    std::memcpy(records.data() + i * sizeof(SensorRecord), &record, sizeof record);
  }
  return records;
}

std::vector<Sensor> decodeSensors(std::string_view records, const SceneStore& scene) {
  if (records.size() % sizeof(SensorRecord) != 0)
    throw std::runtime_error(fmt::format("the job's sensors are {} bytes, not whole records", records.size()));
  std::vector<Sensor> sensors(records.size() / sizeof(SensorRecord));
  for (size_t i = 0; i < sensors.size(); ++i) {
    SensorRecord record;
    std::memcpy(&record, records.data() + i * sizeof(SensorRecord), sizeof record);
    Sensor& s = sensors[i];
    s.position = Vec3(record.position[0], record.position[1], record.position[2]);
    s.direction = Vec3(record.direction[0], record.direction[1], record.direction[2]);
    s.sourceLine = record.line;
    s.cell = record.cell;
    if (s.cell >= int64_t(scene.cells().size()))
      throw std::runtime_error(fmt::format("sensor {} lies in cell {}, which scene {} lacks", i, s.cell,
                                           scene.directory()));
    if (s.cell >= 0) s.room = scene.cells()[size_t(s.cell)].name;
  }
  return sensors;
}

size_t sensorsOutsideCells(std::string_view records) {
  size_t outside = 0;
  for (size_t at = 0; at + sizeof(SensorRecord) <= records.size(); at += sizeof(SensorRecord)) {
    SensorRecord record;
    std::memcpy(&record, records.data() + at, sizeof record);
    outside += record.cell < 0;
  }
  return outside;
}

void queueSensors(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const std::vector<Sensor>& sensors) {
  std::map<uint32_t, std::vector<uint32_t>> byCell;
  for (size_t i = 0; i < sensors.size(); ++i)
    if (sensors[i].cell >= 0) byCell[uint32_t(sensors[i].cell)].push_back(uint32_t(i));
  const uint32_t spp = std::max(1u, spec.getSpp());
  const size_t perBatch = std::max<size_t>(1, kSensorSamplesPerBatch / spp);
  for (const auto& [cell, indices] : byCell) {
    for (size_t first = 0; first < indices.size(); first += perBatch) {
      const size_t count = std::min(perBatch, indices.size() - first);
      capnp::MallocMessageBuilder message;
      auto list = message.initRoot<wire::RayBatch>().initSensors(unsigned(count));
      for (size_t k = 0; k < count; ++k) {
        const uint32_t index = indices[first + k];
        const Sensor& s = sensors[index];
        auto point = list[unsigned(k)];
        point.setIndex(index);
        point.setLine(s.sourceLine);
        point.setX(s.position.x), point.setY(s.position.y), point.setZ(s.position.z);
        point.setDx(s.direction.x), point.setDy(s.direction.y), point.setDz(s.direction.z);
      }
      store.addBatch(job, cell, 1, BatchKind::Sensors, int64_t(count) * spp, net::packToString(message));
    }
  }
}

}  // namespace portico
