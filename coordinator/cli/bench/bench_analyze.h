// `portico bench analyze`: what a lighting analysis costs (docs/radiance.md).
//
// SCENE_DIR (scene.json, sensors.pts, render_args.txt if lit by daylight,
// radiance_reference.csv if there is one): Radiance and portico side by
// side in one run. The scene is exported for Radiance (`scene export
// FILE.rad`); the same sensors go through `rtrace -I` at increasing
// -ab/-ad and through `portico analyze` at increasing photons and samples.
// Each rung's error is the relative RMS over sensors against a converged
// reference of the same program (Radiance's: radiance_reference.csv, else
// a run at --radiance-reference; portico's: a run at --portico-reference),
// its time the wall time of the whole child (start-up included). Printed
// as a table with the time each needs for 5, 2 and 1 % error; --csv, --plot.
//
// --buildings tower:10,octagon: the scale run. Each generated building gets
// work-plane sensors in every room (--grid auto when portico analyze has
// it, else a .pts written here from the rooms' boxes) and one `portico
// analyze` with --workers: rooms, sensors, time, bytes read, peak memory.
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchAnalyzeOptions {
  std::string sceneDirectory;
  std::string radianceSettings =
      "-ab 2 -ad 128 -aa 0 -lw 1e-3;-ab 4 -ad 512 -aa 0 -lw 1e-4;-ab 6 -ad 2048 -aa 0 -lw 1e-5;"
      "-ab 8 -ad 8192 -aa 0 -lw 1e-6";
  std::string radianceReference = "-ab 20 -ad 8192 -aa 0 -lw 1e-7 -ds 0.01 -dj 0 -dc 1 -dt 0";
  std::string porticoSettings =
      "--photons 50000 --spp 4 --gather 4;--photons 200000 --spp 16 --gather 4;"
      "--photons 800000 --spp 64 --gather 4;--photons 3200000 --spp 256 --gather 4";
  std::string porticoReference = "--photons 8000000 --spp 1024 --gather 8";
  uint32_t workers = 2;
  std::string csv, plot;

  // The scale run.
  std::string buildings;          // "tower:10,octagon": presets, :floors
  std::string storeDirectory;     // where the buildings are generated (kept, reused when present); "" a temporary one
  std::string analyzeArguments;   // more `portico analyze` arguments for the scale run
  std::string memory = "2GiB";    // per worker
};

int runBenchAnalyze(const BenchAnalyzeOptions& options);

}  // namespace portico::cli
