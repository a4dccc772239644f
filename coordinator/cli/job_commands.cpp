#include <capnp/message.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "common/net/client.h"
#include "common/job/sun_time.h"
#include "common/job/worker_tags.h"
#include "common/net/job_spec_wire.h"
#include "common/transport/sky_model.h"
#include "common/util/cli_bounds.h"
#include "common/util/output_path.h"
#include "coordinator/job_limits.h"
#include "coordinator/cli/commands.h"
#include "coordinator/cli/progress.h"

namespace portico::cli {

namespace {
// "A,B,...": exactly `count` finite numbers; nullopt for anything else.
std::optional<std::vector<float>> parseNumbers(const std::string& text, int count) {
  std::vector<float> v(count);
  const char* at = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < count; ++i) {
    const auto [next, error] = std::from_chars(at, end, v[i]);
    if (error != std::errc() || !std::isfinite(v[i])) return std::nullopt;
    at = next;
    if (i + 1 < count) {
      if (at == end || *at != ',') return std::nullopt;
      ++at;
    }
  }
  if (at != end) return std::nullopt;
  return v;
}

// "X,Y,Z": three finite numbers; nullopt for anything else.
std::optional<Vec3> parseVec3(const std::string& text) {
  const auto v = parseNumbers(text, 3);
  if (!v) return std::nullopt;
  return Vec3((*v)[0], (*v)[1], (*v)[2]);
}

CLI::Validator vec3Text() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return parseVec3(text) ? std::string() : fmt::format("'{}' is not three numbers X,Y,Z", text);
      },
      "X,Y,Z");
}

// The job's camera, made on the first camera option; the coordinator
// refuses what cannot trace (an eye outside every cell, look-at == look-from).
void addCameraOptions(CLI::App& command, JobSettings& o) {
  auto camera = [&o]() -> JobCamera& { return o.camera ? *o.camera : o.camera.emplace(); };
  auto* from = command.add_option_function<std::string>(
      "--look-from", [camera](const std::string& t) { camera().lookFrom = *parseVec3(t); },
      "the job's camera: eye point X,Y,Z in metres (default: the store's camera)");
  from->check(vec3Text());
  auto* at = command.add_option_function<std::string>(
      "--look-at", [camera](const std::string& t) { camera().lookAt = *parseVec3(t); },
      "the point X,Y,Z the job's camera looks at");
  at->check(vec3Text());
  from->needs(at);
  at->needs(from);
  command
      .add_option_function<std::string>("--up", [camera](const std::string& t) { camera().up = *parseVec3(t); },
                                        "the job's camera's up direction X,Y,Z (default: the store camera's)")
      ->check(vec3Text())
      ->needs(from);
  command
      .add_option_function<float>("--fov", [camera](float degrees) { camera().fovYDegrees = degrees; },
                                  "the job's camera's full vertical field of view, degrees (default: the store "
                                  "camera's)")
      ->check(realNumber(1e-3, 179.999))
      ->needs(from);
  // Resolved by the coordinator, which reads the store (the client may not).
  command.add_option("--camera", o.cameraName,
                     "a named camera of the store (`portico scene info` lists them; default: the store's default "
                     "camera); not with --look-from");
}
}  // namespace

namespace {
// A sun by date, time and place (docs/daylight.md): the coordinator
// computes its azimuth and elevation at submit, with the store's site
// where no place is given. Returns --sun-time, which the others need.
CLI::Option* addSunTimeOptions(CLI::App& command, DaylightSettings& d) {
  auto sunTime = [&d]() -> SunTime& { return d.sunTime ? *d.sunTime : d.sunTime.emplace(); };
  auto* when = command.add_option_function<std::string>(
      "--sun-time",
      [&d, sunTime](const std::string& text) {
        sunTime().unixSeconds = parseIsoInstant(text);
        d.sun = true;
        if (d.sky == DaylightSettings::Sky::None) d.sky = DaylightSettings::Sky::Preetham;
      },
      "daylight: the sun at this instant, ISO 8601 with its UTC offset (2026-06-21T14:30+02:00, or Z for UTC), "
      "seen from --latitude/--longitude or else the store's site; not with --sun");
  when->check(CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          parseIsoInstant(text);
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "YYYY-MM-DDTHH:MM[:SS]+HH:MM"));
  const struct {
    const char* name;
    std::optional<double> SunTime::*field;
    double most;
    const char* help;
  } places[] = {
      {"--latitude", &SunTime::latitudeDegrees, 90,
       "with --sun-time: degrees north (negative: south; default: the store's site)"},
      {"--longitude", &SunTime::longitudeDegrees, 180,
       "with --sun-time: degrees east (negative: west; default: the store's site)"},
      {"--north-azimuth", &SunTime::northAzimuthDegrees, 360,
       "with --sun-time: the azimuth of geographic north as --sun measures it (from +Z towards +X; default: the "
       "store's site's, else 0: +Z is north, and then east is -X)"}};
  for (const auto& place : places)
    command
        .add_option_function<double>(
            place.name, [sunTime, field = place.field](double degrees) { sunTime().*field = degrees; }, place.help)
        ->check(realNumber(-place.most, place.most))
        ->needs(when);
  return when;
}
}  // namespace

// Sun and sky (docs/daylight.md). Each value is checked as it is read, so
// that a wrong one is refused in one line naming its option.
void addDaylightOptions(CLI::App& command, DaylightSettings& d) {
  using Sky = DaylightSettings::Sky;
  auto* sun = command
      .add_option_function<std::string>(
          "--sun",
          [&d](const std::string& text) {
            const auto v = parseNumbers(text, 2);
            d.sun = true;
            d.sunAzimuthDegrees = (*v)[0];
            d.sunElevationDegrees = (*v)[1];
            if (d.sky == Sky::None) d.sky = Sky::Preetham;
          },
          "daylight: the sun at AZIMUTH,ELEVATION degrees (azimuth from +Z towards +X, elevation above the "
          "horizontal; +Y is up), with a Preetham sky unless --sky says otherwise")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const auto v = parseNumbers(text, 2);
            if (!v) return fmt::format("'{}' is not two numbers AZIMUTH,ELEVATION (degrees)", text);
            DaylightSettings probe;
            probe.sun = true;
            probe.sunAzimuthDegrees = (*v)[0];
            probe.sunElevationDegrees = (*v)[1];
            // CLI11 names the option itself.
            std::string problem = daylightProblem(probe);
            if (problem.rfind("--sun: ", 0) == 0) problem.erase(0, std::string_view("--sun: ").size());
            return problem;
          },
          "AZIMUTH,ELEVATION"));
  addSunTimeOptions(command, d)->excludes(sun);
  command
      .add_option_function<std::string>(
          "--sky",
          [&d](const std::string& text) {
            if (text == "preetham") d.sky = Sky::Preetham;
            else if (text == "overcast") d.sky = Sky::Overcast;
            else {
              d.sky = Sky::Uniform;
              d.skyRadiance = *parseVec3(text.substr(std::string_view("uniform:").size()));
            }
          },
          "daylight's sky: preetham (clear, needs --sun), overcast (CIE, 10 000 lx on the ground) or "
          "uniform:R,G,B (this radiance from every direction)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "preetham" || text == "overcast") return "";
            constexpr std::string_view kUniform = "uniform:";
            const auto radiance = text.rfind(kUniform, 0) == 0 ? parseVec3(text.substr(kUniform.size())) : std::nullopt;
            if (!radiance || std::min({radiance->x, radiance->y, radiance->z}) < 0)
              return fmt::format("'{}' is not preetham, overcast or uniform:R,G,B (radiance >= 0)", text);
            return "";
          },
          "preetham|overcast|uniform:R,G,B"));
  command
      .add_option_function<std::string>(
          "--sun-irradiance", [&d](const std::string& text) { d.sunIrradiance = *parseVec3(text); },
          "the sun's irradiance R,G,B on a plane facing it (default: from its elevation and --turbidity)")
      ->check(vec3Text());
  command.add_option("--turbidity", d.turbidity, "haze of the Preetham sky and the sun model (2: very clear, 10: hazy)")
      ->capture_default_str()
      ->check(realNumber(1.7, 10));
}

void addRenderOptions(CLI::App& command, JobSettings& o) {
  addCameraOptions(command, o);
  command.add_option("STORE", o.store, "scene store directory")->required()->check(CLI::ExistingDirectory);
  command.add_option("-o,--output", o.output, "image to write: .png (tone-mapped) or .exr (linear)")->required();
  addLightingOptions(command, o, "samples per pixel");
  command.add_option("--width", o.width, "image width (default: the camera's)")
      ->check(wholeNumber(1, limits::kMaxImageSide));
  command.add_option("--height", o.height, "image height (default: the camera's)")
      ->check(wholeNumber(1, limits::kMaxImageSide));
  // Render passes (coordinator/render_passes.h): without a target or a
  // time limit, one pass, as ever.
  command
      .add_option_function<double>(
          "--target-error", [&o](double error) { o.targetError = error; },
          "render in passes until the estimated relative standard error of 16x16 blocks is at most this "
          "(0.02: 2 %; estimated from 2 passes on)")
      ->check(positiveNumber(limits::kMaxTargetError));
  command
      .add_option_function<double>(
          "--time-limit", [&o](double seconds) { o.timeLimitSeconds = seconds; },
          "render in passes, starting none predicted to end past this many seconds of render (at least one pass)")
      ->check(positiveNumber(limits::kMaxTimeLimitSeconds));
  command
      .add_option("--max-passes", o.maxPasses,
                  fmt::format("most render passes, each of --spp samples per pixel (default: {} with --target-error "
                              "or --time-limit, else 1; alone, exactly this many)",
                              kProgressiveMaxPasses))
      ->check(wholeNumber(1, limits::kMaxPasses));
  command.add_option("--exposure", o.exposure, "PNG exposure")
      ->capture_default_str()
      ->check(realNumber(limits::kMinExposure, limits::kMaxExposure));
  command
      .add_option_function<std::string>(
          "--aov",
          [&o](const std::string& name) {
            o.aov = name == "cells"     ? JobSettings::Aov::Cells
                    : name == "portals" ? JobSettings::Aov::Portals
                                        : JobSettings::Aov::Radiance;
            // Luminance is the radiance render written in cd/m^2.
            if (name == "luminance" && !o.luminance) o.luminance.emplace();
          },
          "what the image shows: radiance; luminance (cd/m^2, 179 x Rec. 709 Y per pixel, to .exr, .hdr or "
          ".tif); cells (false colour of each pixel's cell); portals (portals each camera ray crossed: blue 0 ... "
          "red 7, white 8+)")
      ->check(CLI::IsMember({"radiance", "luminance", "cells", "portals"}))
      ->default_str(toString(o.aov));
  addFalseColorOptions(command, o);
}

// `--falsecolor` and its scale, as Radiance's `falsecolor` takes them (-s
// maximum, -log decades, -n steps); each implies `--aov luminance`.
void addFalseColorOptions(CLI::App& command, JobSettings& o) {
  const auto falseColor = [&o]() -> LuminanceImage& {
    if (!o.luminance) o.luminance.emplace();
    o.luminance->falseColor = true;
    return *o.luminance;
  };
  command.add_flag_callback(
      "--falsecolor", [falseColor] { falseColor(); },
      "also write OUTPUT.falsecolor.png: the luminance on a false-colour scale with a legend in cd/m^2 (implies "
      "--aov luminance)");
  command
      .add_option_function<double>(
          "--falsecolor-max", [falseColor](double maximum) { falseColor().falseColorMaximum = maximum; },
          "cd/m^2 at the top of the false-colour scale (default: the image's 95th percentile, rounded up)")
      ->check(positiveNumber(kMaxFalseColorMaximum));
  command
      .add_option_function<uint32_t>(
          "--falsecolor-log", [falseColor](uint32_t decades) { falseColor().falseColorDecades = decades; },
          "a logarithmic false-colour scale over this many decades below its top (default: linear from 0)")
      ->check(wholeNumber(1, kMaxFalseColorDecades));
  command
      .add_option_function<uint32_t>(
          "--falsecolor-steps", [falseColor](uint32_t steps) { falseColor().falseColorSteps = steps; },
          "intervals of the false-colour legend (default 8)")
      ->check(wholeNumber(1, kMaxFalseColorSteps));
}

void addLightingOptions(CLI::App& command, JobSettings& o, const std::string& samplesHelp) {
  addDaylightOptions(command, o.daylight);
  command.add_option("--accel", o.accel,
                     "per-cell accelerator: grid[:res=N], hgrid, kd:median, kd:sah, kd:bbox, embree, brute, or auto "
                     "(chosen per cell by a calibrated cost model; `portico bench calibrate`)")->capture_default_str();
  command.add_option("--render-accel", o.renderAccel,
                     "accelerator of the render phase (default: bvh with --accel auto, the default, or grid; else "
                     "the --accel)");
  // Bounded as the coordinator bounds them (coordinator/job_limits.h): a
  // wrong value is refused here, in one line, before anything starts.
  command.add_option("--photons", o.photons,
                     "photons emitted in all (default: 5000 per light of the building, at least 400000, at most "
                     "20000000; docs/large-buildings.md)")
      ->check(wholeNumber(1, limits::kMaxPhotons));
  command.add_option("--spp", o.spp, samplesHelp)->capture_default_str()->check(wholeNumber(1, limits::kMaxSpp));
  command.add_option("--gather", o.gather, "final-gather rays per hit (0: photon-map estimate at the hit)")
      ->capture_default_str()
      ->check(wholeNumber(0, limits::kMaxGather));
  command.add_option("--seed", o.seed, "random seed")->capture_default_str()->check(wholeNumber(0, UINT64_MAX));
  command.add_option("--light-samples", o.lightSamples, "shadow rays per camera hit")
      ->capture_default_str()
      ->check(wholeNumber(0, limits::kMaxLightSamples));
  command.add_option("--light-hops", o.lightHops,
                     "sample the lights of cells within this many portals of a shading point (-1: every light; "
                     "default: 2 with room cells, every light with --grid voxel cells)")
      ->check(wholeNumber(-1, limits::kMaxLightHops));
  command
      .add_option_function<std::string>(
          "--light-sampler",
          [&o](const std::string& name) { o.lightSampling = name == "scan" ? LightSampling::Scan : LightSampling::Tree; },
          "how a shading point chooses among those lights: tree (one descent of a light tree, ~2 log2(n) of them "
          "looked at) or scan (every one weighed; docs/many-lights.md)")
      ->check(CLI::IsMember({"tree", "scan"}))
      ->default_str(toString(o.lightSampling));
  command.add_option("--photon-k", o.photonK, "photons per density estimate")
      ->capture_default_str()
      ->check(wholeNumber(1, limits::kMaxPhotonK));
  command.add_option("--photon-radius", o.photonRadius, "largest density-estimate radius (m)")
      ->capture_default_str()
      ->check(realNumber(1e-6, limits::kMaxPhotonRadius));
  command
      .add_option_function<std::string>(
          "--irradiance",
          [&o](const std::string& name) {
            o.irradiance = name == "knn" ? JobSettings::Irradiance::Knn : JobSettings::Irradiance::Precomputed;
          },
          "what a final-gather hit reads: precomputed (the nearest irradiance precomputed at about one "
          "photon in 8 of its cell) or knn (the k-nearest-photon estimate at every hit)")
      ->check(CLI::IsMember({"precomputed", "knn"}))
      ->default_str(toString(o.irradiance));
  command.add_flag("--fresh-photons", o.freshPhotons,
                   "run a photon pass of its own, even where an earlier job's finished one on the same store with "
                   "the same photon settings could be reused");
}

void addConnectOptions(CLI::App& command, ConnectOptions& o) {
  command.add_option("--coordinator", o.endpoint, "coordinator endpoint")->required();
  command.add_option("--keys", o.keys, "CURVE keys directory (`portico keys generate`), as the coordinator's")
      ->check(CLI::ExistingDirectory);
  command.add_option("--timeout", o.timeoutSeconds, "seconds to wait for each answer")
      ->capture_default_str()
      ->check(realNumber(0.001, 1e6));
}

namespace {
net::CoordinatorClient connectTo(const ConnectOptions& o, net::Role role = net::Role::Client) {
  return net::CoordinatorClient(o.endpoint, o.keys,
                                std::chrono::milliseconds(static_cast<int64_t>(o.timeoutSeconds * 1000)), role);
}

// Written beside its name and renamed, as the coordinator writes images.
void writeWhole(const std::string& path, const void* data, size_t size) {
  const std::string temporary = path + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(static_cast<const char*>(data), std::streamsize(size));
    out.close();
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write: {}", temporary, std::strerror(errno)));
  }
  std::filesystem::rename(temporary, path);
}
}  // namespace

void fillSubmit(const JobSettings& o, capnp::MallocMessageBuilder& message, const std::vector<Sensor>* sensors) {
  if (const std::string problem = cameraChoiceProblem(o); !problem.empty()) throw std::invalid_argument(problem);
  if (const std::string problem = luminanceProblem(o); !problem.empty()) throw std::invalid_argument(problem);
  if (const std::string problem = daylightProblem(o.daylight); !problem.empty()) throw std::invalid_argument(problem);
  JobSettings settings = o;
  settings.store = std::filesystem::absolute(o.store).lexically_normal().string();
  // As the user who asks: the coordinator checks it again as itself.
  checkOutputPath(o.output, o.analysis ? OutputKind::AnalysisCsv : OutputKind::Image);
  settings.output = std::filesystem::absolute(o.output).lexically_normal().string();
  // Automatic values stay automatic: the coordinator resolves them (resolveJobSettings).
  auto submit = message.initRoot<wire::Envelope>().initSubmit();
  toWire(settings, submit.initSpec());
  submit.setFreshPhotons(settings.freshPhotons);
  if (sensors) {
    auto points = submit.initSensors(unsigned(sensors->size()));
    for (size_t i = 0; i < sensors->size(); ++i) {
      const Sensor& s = (*sensors)[i];
      auto point = points[unsigned(i)];
      point.setIndex(uint32_t(i));
      point.setLine(s.sourceLine);
      point.setX(s.position.x), point.setY(s.position.y), point.setZ(s.position.z);
      point.setDx(s.direction.x), point.setDy(s.direction.y), point.setDz(s.direction.z);
    }
  }
}

int runSubmit(const ConnectOptions& connect, const JobSettings& render, const Placement& placement,
              const std::vector<Sensor>* sensors) {
  capnp::MallocMessageBuilder message;
  fillSubmit(render, message, sensors);
  auto submit = message.getRoot<wire::Envelope>().getSubmit();
  submit.setPriority(placement.priority);
  const std::vector<std::string> tags = normalizedTags(placement.requiredTags, "--require");
  auto required = submit.initRequiredTags(static_cast<unsigned>(tags.size()));
  for (size_t i = 0; i < tags.size(); ++i) required.set(static_cast<unsigned>(i), tags[i]);
  net::CoordinatorClient client = connectTo(connect);
  std::cout << client.submit(message) << "\n";
  return 0;
}

int runStatus(const ConnectOptions& connect, uint64_t job, bool json) {
  net::CoordinatorClient client = connectTo(connect);
  const auto status = nlohmann::json::parse(client.statusJson(job));
  if (json) {
    std::cout << status.dump() << "\n";
    return 0;
  }
  std::cout << describeStatus(status);
  return 0;
}

int runWait(const ConnectOptions& connect, uint64_t job, bool quiet) {
  net::CoordinatorClient client = connectTo(connect);
  ProgressDisplay display(quiet);
  for (;;) {
    const auto status = nlohmann::json::parse(client.statusJson(job));
    display.update(status);
    const std::string state = status.value("state", "");
    if (jobEnded(state)) {
      display.finish(status);
      // Done, but its image could not be written: the status says how to get it.
      return state == "done" && status.value("error", "").empty() ? 0 : 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
}

int runCancel(const ConnectOptions& connect, uint64_t job) {
  net::CoordinatorClient client = connectTo(connect);
  const auto status = nlohmann::json::parse(client.cancel(job));
  std::cout << fmt::format("job {}: {}\n", job, status.value("state", "?"));
  return 0;
}

int runPriority(const ConnectOptions& connect, uint64_t job, int32_t priority) {
  net::CoordinatorClient client = connectTo(connect);
  const auto status = nlohmann::json::parse(client.setPriority(job, priority));
  std::cout << fmt::format("job {}: {}, priority {}\n", job, status.value("state", "?"), status.value("priority", 0));
  return 0;
}

int runFetchImage(const ConnectOptions& connect, uint64_t job, const std::string& output) {
  net::CoordinatorClient client = connectTo(connect);
  auto reply = client.fetchImage(job);
  auto image = reply->envelope().getImage();
  const std::string path = output.empty() ? std::string(image.getOutput().cStr()) : output;
  // The format follows the job's output; another extension would mislabel the bytes.
  const auto extension = [](const std::string& p) { return std::filesystem::path(p).extension().string(); };
  if (extension(path) != extension(image.getOutput().cStr()))
    throw std::invalid_argument(fmt::format("{}: job {}'s image is a {} file (its output was {})", path, job,
                                            extension(image.getOutput().cStr()), image.getOutput().cStr()));
  checkOutputPath(path, extension(path) == ".csv" ? OutputKind::AnalysisCsv : OutputKind::Image);
  writeWhole(path, image.getImage().begin(), image.getImage().size());
  const std::string statistics = image.getStatistics();
  writeWhole(path + ".json", statistics.data(), statistics.size());
  std::cout << fmt::format("job {}: wrote {} ({} bytes) and {}.json\n", job, path, image.getImage().size(), path);
  return 0;
}

int runShutdown(const ConnectOptions& connect) {
  // A coordinator that stops answers Shutdown; one that refuses answers an
  // Error (which request() throws); no answer is no shutdown either.
  net::CoordinatorClient client(connect.endpoint, connect.keys,
                                std::chrono::milliseconds(static_cast<int64_t>(connect.timeoutSeconds * 1000)),
                                net::Role::Operator);
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().setShutdown();
  const auto reply = client.request(message);
  if (reply->envelope().which() != wire::Envelope::SHUTDOWN)
    throw std::runtime_error(fmt::format("coordinator at {} sent an unexpected reply to Shutdown", connect.endpoint));
  std::cout << "coordinator at " << connect.endpoint << " is stopping\n";
  return 0;
}

}  // namespace portico::cli
