#include "coordinator/result_check.h"

#include <fmt/format.h>

#include <string_view>

#include "common/transport/film.h"
#include "common/transport/photon_record.h"
#include "common/transport/trace_counters.h"

namespace portico {

void LeaseExpectation::add(wire::RayBatch::Reader batch, uint32_t spp) {
  switch (batch.which()) {
    case wire::RayBatch::EMIT: photonsToEmit += batch.getEmit().getCount(); break;
    case wire::RayBatch::CAMERA: cameraSamples += int64_t(batch.getCamera().getPixelCount()) * spp; break;
    case wire::RayBatch::RAYS: raysIn += int64_t(batch.getRays().size()); break;
    // An analysis's sensors: each of their samples counts as a camera ray.
    case wire::RayBatch::SENSORS:
      sensors += int64_t(batch.getSensors().size());
      cameraSamples += int64_t(batch.getSensors().size()) * spp;
      break;
  }
}

namespace {
// The counters the checks read; any other is only required to be >= 0.
struct ResultCounters {
  int64_t emitted = 0, absorbed = 0, escaped = 0, deposits = 0, copies = 0;
  int64_t camera = 0, rayCrossings = 0, invalid = 0, filmOutOfRange = 0;
  int64_t emission = 0, shadow = 0, gather = 0, finished = 0, sensorsMeasured = 0;
};

ResultCounters readCounters(wire::Result::Reader result) {
  ResultCounters c;
  for (auto counter : result.getCounters()) {
    const std::string_view name = counter.getName().cStr();
    const int64_t value = counter.getValue();
    if (value < 0) throw BadResultError(fmt::format("its counter {} is {}: counts are never negative", name, value));
    if (name == "photons.emitted") c.emitted = value;
    else if (name == "photons.absorbed") c.absorbed = value;
    else if (name == "photons.escaped") c.escaped = value;
    else if (name == "photons.deposits") c.deposits = value;
    else if (name == "photons.portal_copies") c.copies = value;
    else if (name == "rays.camera") c.camera = value;
    else if (name == "rays.crossings") c.rayCrossings = value;
    else if (name == "rays.invalid") c.invalid = value;
    else if (name == "rays.emission") c.emission = value;
    else if (name == "rays.shadow") c.shadow = value;
    else if (name == "rays.gather") c.gather = value;
    else if (name == "rays.finished") c.finished = value;
    else if (name == "sensors.measured") c.sensorsMeasured = value;
    else if (name == kFilmOutOfRangeCounter) c.filmOutOfRange = value;
  }
  return c;
}

int64_t raysHandedOn(wire::Result::Reader result) {
  int64_t rays = 0;
  for (auto crossing : result.getCrossings()) rays += int64_t(crossing.getRays().size());
  return rays;
}

// Records in the Result and in the lease's deposit region (whole records
// or not: regionDeposits and the copy into jobs.db refuse partial ones).
int64_t depositRecords(wire::Result::Reader result) {
  int64_t bytes = 0;
  for (auto deposits : result.getDeposits()) bytes += int64_t(deposits.getRecords().size() + deposits.getFileSize());
  return bytes / int64_t(sizeof(PhotonRecord));
}
}  // namespace

void checkResultCounts(const LeaseExpectation* expected, int phase, wire::Result::Reader result) {
  const ResultCounters c = readCounters(result);
  // A tracer that meets a contribution beyond the film's range counts it
  // and leaves it out: the Result is incomplete. Every worker does the
  // same on such a scene, which is how the job comes to fail (refuseResult).
  if (c.filmOutOfRange != 0) throw FilmRangeError();
  if (phase == 0) {
    if (result.getFilm().size() != 0)
      throw BadResultError(fmt::format("a photon lease's Result holds {} film values", result.getFilm().size()));
    if (expected) {
      if (c.emitted != expected->photonsToEmit)
        throw BadResultError(
            fmt::format("it emitted {} photons, its lease asked for {}", c.emitted, expected->photonsToEmit));
      const int64_t started = c.emitted + expected->raysIn;
      const int64_t ended = c.absorbed + c.escaped + raysHandedOn(result) + c.invalid;
      if (started != ended)
        throw BadResultError(fmt::format("its photons do not add up: {} emitted + {} received != {} absorbed + {} "
                                         "escaped + {} handed on + {} invalid",
                                         c.emitted, expected->raysIn, c.absorbed, c.escaped, raysHandedOn(result),
                                         c.invalid));
    }
    const int64_t records = depositRecords(result);
    if (records > c.deposits + c.copies)
      throw BadResultError(fmt::format("it holds {} deposit records for {} deposits and {} portal copies", records,
                                       c.deposits, c.copies));
    return;
  }
  if (result.getDeposits().size() != 0)
    throw BadResultError(fmt::format("a render lease's Result holds deposits for {} cells", result.getDeposits().size()));
  // Every ray handed on crossed a portal, counted as it did (those traced
  // on in cells the worker holds are counted but not handed on).
  if (const int64_t handedOn = raysHandedOn(result); handedOn > c.rayCrossings)
    throw BadResultError(fmt::format("it hands on {} rays for {} portal crossings", handedOn, c.rayCrossings));
  if (!expected) return;
  if (c.camera != expected->cameraSamples)
    throw BadResultError(
        fmt::format("it traced {} camera rays, its lease asked for {}", c.camera, expected->cameraSamples));
  if (c.invalid > expected->raysIn)
    throw BadResultError(fmt::format("it counts {} invalid rays of the {} it received", c.invalid, expected->raysIn));
  if (c.sensorsMeasured != expected->sensors)
    throw BadResultError(
        fmt::format("it measured {} sensors, its lease asked for {}", c.sensorsMeasured, expected->sensors));
  // Every ray it started (its camera samples, the rays it received, and the
  // emission, shadow and gather rays it spawned) ended once: in it, or
  // handed on. Rays it traced on in cells it holds (rays.forwarded) left
  // its crossings and ended there, so they count once too.
  const int64_t started = c.camera + c.emission + expected->raysIn + c.shadow + c.gather;
  const int64_t handedOn = raysHandedOn(result);
  if (started != c.finished + c.invalid + handedOn)
    throw BadResultError(fmt::format("its rays do not add up: {} camera + {} emission + {} received + {} shadow + {} "
                                     "gather != {} finished + {} invalid + {} handed on",
                                     c.camera, c.emission, expected->raysIn, c.shadow, c.gather, c.finished,
                                     c.invalid, handedOn));
}

void checkFilmValue(wire::PixelSum::Reader pixel, uint64_t pixelCount) {
  if (pixel.getPixel() >= pixelCount)
    throw BadResultError(fmt::format("film value for pixel {}, outside the image ({} pixels)", pixel.getPixel(),
                                     pixelCount));
  for (const int64_t value : {pixel.getR(), pixel.getG(), pixel.getB()})
    if (value < 0 || value > kFilmMaxSum)
      throw BadResultError(fmt::format("film value {} at pixel {}: a film value is within [0, {}]", value,
                                       pixel.getPixel(), kFilmMaxSum));
}

}  // namespace portico
