// `portico bench quality DIR`: error against time on a reference scene
// (scene.json with reference.exr beside it) or a named camera of a generated
// building (view.json: generator arguments, camera, image size; with
// reference.exr). Imports or generates the store once, renders it with each setting of a ladder through `portico render` (the
// whole command timed, start-up included), scores each image with
// `portico-compare` and prints one CSV row per setting: seconds, mean
// error, worst block, block RMSE (16x16 blocks, those under 5 % of the
// image mean skipped). With --mitsuba, Mitsuba 3's path tracer renders the
// same scene at each of --mitsuba-spp in the same run, and with --luxcore
// LuxCoreRender at each of --luxcore-spp (peer_ladder.h), scored the same
// way, one row each.
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchQualityOptions {
  std::string sceneDirectory;
  // `portico render` arguments per rung, rungs separated by ';'.
  std::string settings = "--spp 4 --gather 2;--spp 8 --gather 4;--spp 16 --gather 4;--spp 32 --gather 8";
  uint32_t workers = 2;   // and Mitsuba's threads
  bool mitsuba = false;
  std::string mitsubaSpp = "16,64,256";
  std::string mitsubaPython;   // empty: defaultMitsubaPython()
  bool luxcore = false;
  std::string luxcoreSpp = "16,64,256";
  // At most this many photons in its PhotonGI cache (LuxCore's own default,
  // which stops sooner where the cache converges); 0: its plain path tracer.
  uint64_t luxcorePhotonGi = 100000000;
  std::string csv;
  std::string plot;
};

int runBenchQuality(const BenchQualityOptions& options);

}  // namespace portico::cli
