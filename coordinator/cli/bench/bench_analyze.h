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
// the work-plane grid of `analyze --grid auto` in every room (`portico
// scene grid`) and one `portico analyze` of it with --workers: rooms,
// sensors, time, bytes read, peak memory.
#pragma once

#include <cstdint>
#include <string>

namespace portico::cli {

struct BenchAnalyzeOptions {
  std::string sceneDirectory;
  // Russian roulette (-lr -N) rather than rtrace's default -lr 7, which cuts
  // every path after 7 reflections, ambient ones included: a ladder of -ab
  // beyond 7 would converge to a darker answer (tests/tools/radiance_reference.py).
  std::string radianceSettings =
      "-ab 2 -lr -4 -ad 128 -aa 0 -lw 1e-3;-ab 4 -lr -8 -ad 512 -aa 0 -lw 1e-4;-ab 8 -lr -16 -ad 2048 -aa 0 -lw 1e-5;"
      "-ab 16 -lr -32 -ad 8192 -aa 0 -lw 1e-6";
  std::string radianceReference = "-ab 40 -lr -80 -ad 8192 -aa 0 -lw 1e-7 -ds 0.01 -dj 0 -dc 1 -dt 0";
  std::string porticoSettings =
      "--photons 100000 --spp 4 --gather 4;--photons 200000 --spp 16 --gather 8;"
      "--photons 400000 --spp 64 --gather 16;--photons 800000 --spp 256 --gather 32";
  std::string porticoReference = "--photons 4000000 --spp 1024 --gather 64";
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
