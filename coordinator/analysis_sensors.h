// An analysis job's sensors at the coordinator: taken from the Submit
// (checked, and each located in the smallest cell containing it), kept in
// jobs.db with the job, queued by cell for its render phase as camera rays
// are, and read back for its results.
//
// A sensor outside every cell is kept, with no cell: it is not measured,
// and its row of the results has empty readings (the statistics and the
// CSV name its line). A job none of whose sensors lies in a cell is refused.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

// Sensor samples handed to one sensor batch: small, so that even the few
// hundred sensors of one room make several leases for several workers.
constexpr uint32_t kSensorSamplesPerBatch = 2048;

// The Submit's sensors, in its order, with their cells and rooms. Throws
// std::invalid_argument naming the sensor (and its line) that is not a
// finite point with a non-zero direction, or when none lies in a cell.
std::vector<Sensor> sensorsOfSubmit(capnp::List<wire::SensorPoint>::Reader points, const SceneStore& scene);

// jobs.db's form: fixed-size records in the sensors' order.
std::string encodeSensors(const std::vector<Sensor>& sensors);
// Their rooms named from `scene`'s cells. Throws on records of the wrong size.
std::vector<Sensor> decodeSensors(std::string_view records, const SceneStore& scene);

// How many of the records' sensors lie outside every cell (not measured).
size_t sensorsOutsideCells(std::string_view records);

// The job's sensor batches (the sensors within a cell), for its render phase.
void queueSensors(JobStore& store, uint64_t job, wire::JobSpec::Reader spec, const std::vector<Sensor>& sensors);

}  // namespace portico
