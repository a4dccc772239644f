// An analysis job's results: each sensor's reading from the job's film
// (common/analysis/sensor_film.h) and the CSV they are written as, one row
// per sensor in the sensor file's order (docs/lighting-analysis.md):
//
//   index,room,x,y,z,dx,dy,dz,irradiance_r,irradiance_g,irradiance_b,lux,
//   standard_error_lux,direct_share[,daylight_factor]
//
// index counts the file's sensors from 0; irradiance is W/m^2 per RGB
// channel; lux = 179 x Rec. 709 Y; daylight_factor (with --daylight-factor)
// is 100 E / E_out in %. A sensor outside every cell has an empty room and
// empty readings.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/analysis/sensor.h"
#include "common/scene/store/scene_store.h"
#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

struct AnalysisResults {
  std::vector<Sensor> sensors;            // in the sensor file's order
  std::vector<SensorReading> readings;    // one per sensor (zero where sensor.cell < 0)
  // With --daylight-factor: the unobstructed horizontal illuminance of the
  // job's sky, E_out (lux), in closed form.
  std::optional<double> outdoorLux;
  bool measured(size_t i) const { return sensors[i].cell >= 0; }
};

AnalysisResults analysisResults(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec,
                                const SceneStore& scene);
std::string analysisCsv(const AnalysisResults& results);
// Writes the results' files: `output` (analysisCsv), each written whole
// beside its name and renamed. The place for every report made from them.
void writeAnalysisOutputs(const AnalysisResults& results, const std::string& output);

}  // namespace portico
