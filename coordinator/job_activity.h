// What `portico dashboard` asks of a job beyond its status
// (JobDetailRequest, FetchPreview): where its work is, cell by cell, and its
// film so far, made small. Read from jobs.db and the worker registry at the
// dashboard's bounded rate, never on the scheduling path.
#pragma once

#include <nlohmann/json.hpp>

#include "common/image/linear_image.h"
#include "coordinator/job_store.h"
#include "coordinator/worker_registry.h"
#include "proto/wire.capnp.h"

namespace portico {

// {"job", "phase", "cells": [{"cell", "pending", "leased_by", "done", "loads"}]}:
// every cell with work pending (queued or leased: rays or photons to trace),
// leased now (the workers holding it), traced in the job's current phase
// (its lease log; every traced cell once the job ended) or loaded by a
// worker at all ("accel.cell.N": the load count shown on hover).
nlohmann::json cellActivity(JobStore& store, const JobRecord& job, const WorkerRegistry& workers);

// The longest side a preview may have, whatever is asked.
inline constexpr uint32_t kMaxPreviewSide = 1024;

// `film` box-filtered down to at most maxSide (0: kMaxPreviewSide) pixels
// on its longer side, by a whole factor, so every preview pixel is the mean
// of the same number of film pixels (fewer at the right and bottom edges).
LinearImage shrinkImage(const LinearImage& film, uint32_t maxSide);

}  // namespace portico
