// The cluster model: a discrete-event simulation of a finished job on N
// workers, from the job's own lease log (JobStore::leaseLog): on N machines
// (a cluster), or all on one machine of C cores with the coordinator (the
// machine a record was measured on). It schedules with the coordinator's
// own code, on a simulated clock: WorkerInfo (lease sizing, speed and
// load-cost estimates, leases in flight), CellCacheModel, chooseCell and
// addMoreCells. What it models rather than runs: the leases (each cell's
// measured cost per unit of work, without what waiting for a core added to
// it), each worker's cell cache (its --memory, the worker's own LRU
// eviction, the bytes a loaded cell takes there), which decides every
// lease's loads, at the record's measured load seconds per triangle of each
// cell; the coordinator, one thread that spends its measured CPU per lease
// plus what chooseCell costs it at N workers, timed here (CPU); and the cores
// they share (SharedCores). docs/large-buildings.md, "Cluster model".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/scene/store/scene_types.h"
#include "coordinator/job_store.h"

namespace portico {

// What the model knows of a job: its cells, its lease log, the
// coordinator's measured CPU per lease, the time it took before the photon
// pass's first lease, and between the photon pass's last Result and the
// render's first lease (queuing the camera rays).
struct ClusterRecord {
  std::vector<CellInfo> cells;
  std::vector<LeaseLogEntry> leases;
  double coordinatorSecondsPerLease = 0;
  double phaseChangeSeconds = 0;
  // From the job's start to the photon pass's first lease (the coordinator
  // plans the job and queues its emission).
  double phaseStartSeconds = 0;
};

struct ClusterModelOptions {
  size_t workers = 1;
  uint64_t workerMemoryBytes = uint64_t(1) << 30;
  // One way through the network, coordinator to worker or back.
  double latencySeconds = 100e-6;
  // What a loaded cell takes in a worker's cache per byte of its file
  // (geometry and accelerator), in the photon pass and in the render (its
  // own structure): decides when a modelled worker drops a cell.
  double cachedBytesPerFileByte[2] = {3, 3};
  // 0: the coordinator and each worker on a machine of its own. C > 0:
  // all of them on one machine of C cores (processor sharing).
  double hostCores = 0;
  // The photon pass's tracing work times this, its loads as the caches
  // make them, the render as recorded: a job of F times the photons on the
  // same building, rendering the same image.
  double workScale = 1;
  // Each lease's work times this (WorkerInfo::kLeaseSeconds and the
  // coordinator's --lease-rays with it): fewer, longer leases.
  double leaseScale = 1;
  // The coordinator's CPU per lease: < 0, the record's own (its CPU from
  // submit to last Result over its leases); else this, e.g. what
  // `portico bench coordinator` measures for the coordinator alone.
  double coordinatorSecondsPerLease = -1;
  // The bytes a lease moves through the coordinator per unit of its work,
  // in the photon pass and in the render (its Assign and Result: rays
  // handed on, deposits sent; a render's photon tables), and the
  // coordinator's network link: each lease holds the coordinator for its
  // bytes' time on the link too (0: not charged). One link serves every
  // worker, as one thread serves their messages.
  double bytesPerWork[2] = {0, 0};
  double linkBytesPerSecond = 0;
};

struct PhasePrediction {
  double seconds = 0;
  int64_t leases = 0;
  // Cells loaded: every load of the simulated caches; from a record that
  // does not name its leases' more cells (schema 9 and before), the second
  // copies beyond the record's own loads, which recur as recorded.
  int64_t loads = 0;
  bool simulatedCaches = false;
  double coordinatorBusySeconds = 0;   // its CPU in the phase
  double workerBusySeconds = 0;        // all workers' tracing and loads
};

struct ClusterPrediction {
  PhasePrediction phases[2];           // photons, render
  double seconds() const { return phases[0].seconds + phases[1].seconds; }
  // The coordinator's share of the wall time it was busy: near 1, it is
  // the bottleneck (workers wait for leases).
  double coordinatorUtilization() const;
  double workerUtilization(size_t workers) const;
  double chooseCellMicros = 0;         // the real chooseCell's mean time per call here
  int64_t chooseCellCalls = 0;         // a call per lease, and one per worker it found nothing for
};

// Each phase queues the lease log's work per cell, in pieces of the
// recorded leases' sizes: a cell's first piece from the start, its later
// ones as the phase's progress reaches where the record had them queued;
// the render phase after the last photon lease and the recorded phase
// change, with its own accelerators: cells held from the photon pass are
// loaded again (the worker's cache keys them by structure).
ClusterPrediction simulateCluster(const ClusterRecord& record, const ClusterModelOptions& options);

}  // namespace portico
