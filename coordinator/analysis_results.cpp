#include "coordinator/analysis_results.h"

#include <fmt/format.h>

#include <stdexcept>

#include "common/analysis/sensor_film.h"
#include "common/net/job_spec_wire.h"
#include "common/transport/sky_model.h"
#include "common/util/atomic_file.h"
#include "common/util/csv_field.h"
#include "coordinator/analysis_sensors.h"

namespace portico {

AnalysisResults analysisResults(JobStore& store, const JobRecord& job, wire::JobSpec::Reader spec,
                                const SceneStore& scene) {
  if (!spec.hasAnalysis()) throw std::logic_error("a job without analysis has no sensor readings");
  AnalysisResults results;
  results.sensors = decodeSensors(store.jobSensors(job.id), scene);
  if (results.sensors.size() != spec.getAnalysis().getSensors())
    throw std::runtime_error(fmt::format("job {} holds {} sensors, its spec says {}", job.id, results.sensors.size(),
                                         spec.getAnalysis().getSensors()));
  const std::vector<FixedRgb> film = store.film(job.id, uint64_t(kSensorFilmColumns) * results.sensors.size());
  results.readings.resize(results.sensors.size());
  for (size_t i = 0; i < results.sensors.size(); ++i)
    if (results.measured(i)) results.readings[i] = sensorReading(film, uint32_t(i), spec.getSpp());
  if (spec.getAnalysis().getDaylightFactor())
    results.outdoorLux = SkyModel(jobSettingsFromWire(spec).daylight).horizontalSkyLux();
  return results;
}

std::string analysisCsv(const AnalysisResults& results) {
  std::string csv =
      "index,room,x,y,z,dx,dy,dz,irradiance_r,irradiance_g,irradiance_b,lux,standard_error_lux,direct_share";
  if (results.outdoorLux) csv += ",daylight_factor";
  csv += "\n";
  for (size_t i = 0; i < results.sensors.size(); ++i) {
    const Sensor& s = results.sensors[i];
    csv += fmt::format("{},{},{},{},{},{},{},{}", i, csvField(s.room), s.position.x, s.position.y, s.position.z,
                       s.direction.x, s.direction.y, s.direction.z);
    if (!results.measured(i)) {
      csv += results.outdoorLux ? ",,,,,,,\n" : ",,,,,,\n";
      continue;
    }
    const SensorReading& r = results.readings[i];
    csv += fmt::format(",{:.6g},{:.6g},{:.6g},{:.6g},{:.4g},{:.4f}", r.irradiance.x, r.irradiance.y, r.irradiance.z,
                       r.lux, r.standardError, r.directShare);
    if (results.outdoorLux) csv += fmt::format(",{:.4g}", 100.0 * r.lux / *results.outdoorLux);
    csv += "\n";
  }
  return csv;
}

void writeAnalysisOutputs(const AnalysisResults& results, const std::string& output) {
  writeFileAtomically(output, analysisCsv(results));
}

}  // namespace portico
