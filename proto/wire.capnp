@0x9621b7a49b1d521a;
# Messages between portico's coordinator, workers and clients (ZeroMQ
# frames, packed encoding). Every frame is one `Envelope`.
using Cxx = import "/capnp/c++.capnp";
$Cxx.namespace("portico::wire");

const protocolVersion :UInt32 = 22;   # 2: fetchFile / fileChunk (cells over the wire); 3: PhotonsReply.error, flat Result frames; 4: Assign.moreCells; 5: 16-byte photon records; 6: JobSpec.irradiance, photons stored with their surface normal; 7: workers receive a complete JobSpec (the coordinator resolves its automatic values); 8: JobSpec.camera; 9: Assign.photonJob (a job may render with an earlier job's photon tables), Submit.freshPhotons; 10: JobSpec.targetError, timeLimit, maxPasses (render passes); 11: JobSpec.cameraName (a store camera by name); 12: JobSpec.daylight (sun and sky); 13: Daylight.sunTime (a sun by date, time and place, in a Submit), a ray's top depth bit marks a shadow ray bound for the sky (toSky); 14: Assign.depositRegion, CellPhotons in the job's photon file (workers sharing the coordinator's file system write their deposits themselves); 15: JobSpec.analysis, RayBatch.sensors, Submit.sensors (lighting analysis: illuminance at sensors); 16: render Results count rays.finished, which the coordinator checks (every ray a lease starts ends in it or is handed on); 17: Heartbeat.progress and tracingLease (the coordinator takes back the leases of a worker that stops moving); 18: JobDetailRequest and Reply, FetchPreview, PreviewReply (the dashboard's cells, log lines and film so far); 19: Submit.priority and requiredTags, Hello.tags, PriorityRequest (priorities and worker pools); 20: JobSpec.luminance (a render's image in cd/m^2, its false-colour picture); 21: JobSpec.lightSampling (light tree or scan); 22: 8-byte photon records (position, direction and power against the job's power unit)

enum Phase {
  photons @0;
  render @1;
}

enum RayKind {
  photon @0;   # carries power; deposits at diffuse hits
  camera @1;   # carries throughput; shades at its first hit
  shadow @2;   # carries the unoccluded contribution; adds it if it reaches tMax
  gather @3;   # final gathering: carries throughput; adds the photon-map radiance where it lands
}

# Everything needed to finish a ray, so a ray never waits on anything else.
# Flat fields (no nested structs) keep a list of rays one contiguous block.
struct Ray {
  kind @0 :RayKind;
  depth @1 :UInt16;        # bounces so far
  pathId @2 :UInt64;       # photon index, or pixel * spp + sample
  pixel @3 :UInt32;
  ox @4 :Float32;
  oy @5 :Float32;
  oz @6 :Float32;
  dx @7 :Float32;
  dy @8 :Float32;
  dz @9 :Float32;
  tMin @10 :Float32;
  tMax @11 :Float32;
  r @12 :Float32;          # power, throughput or contribution
  g @13 :Float32;
  b @14 :Float32;
}

# Photons for one cell's table: those that landed in it, and copies of those
# that landed in a neighbour within the photon radius of their shared portal
# (so density estimates near a doorway see both sides).
struct CellPhotons {
  cell @0 :UInt32;
  records @1 :Data;        # 8-byte photon records on the cell's lattice (common/transport/photon_record.h)
  # Or, in a Result with regionNonce, written by the worker into its lease's
  # deposit region (records empty): where, how many bytes, their CRC-32C.
  fileOffset @2 :UInt64;
  fileSize @3 :UInt64;
  fileCrc @4 :UInt32;
}

# Photon pass: a stretch of the job's photon file (coordinator/append_files.h)
# where a worker that shares the coordinator's file system writes its
# lease's deposits itself, instead of sending them: the coordinator then
# stores where they lie, not the bytes (coordinator/deposit_regions.h). Its
# first block holds a nonce the worker reads and returns (Result.regionNonce),
# which shows that the worker opened the coordinator's file, not one of its
# own of the same name.
struct DepositRegion {
  path @0 :Text;           # the job's photon file, absolute
  offset @1 :UInt64;       # the region's first byte (4 KiB aligned): the nonce block
  size @2 :UInt64;         # bytes, the nonce block included
}

# Work generators: compact descriptions the worker expands itself, so a job
# of a billion photons does not start as a billion queued rays.
struct EmitRange {
  light @0 :UInt32;
  firstPath @1 :UInt64;
  count @2 :UInt32;
  photonsOfLight @3 :UInt64;   # the light's share; each photon carries power / share
}

struct CameraRange {
  firstPixel @0 :UInt32;
  pixelCount @1 :UInt32;
}

# A lighting-analysis sensor (common/analysis/sensor.h): a point and the
# unit normal of its measuring plane. `index` is its place in the job's
# sensor list (the sensor file's order), which is its row of the film;
# `line` its 1-based line in the sensor file (0: placed by a grid).
struct SensorPoint {
  index @0 :UInt32;
  line @1 :UInt32;
  x @2 :Float32;
  y @3 :Float32;
  z @4 :Float32;
  dx @5 :Float32;
  dy @6 :Float32;
  dz @7 :Float32;
}

struct RayBatch {
  union {
    rays @0 :List(Ray);
    emit @1 :EmitRange;
    camera @2 :CameraRange;
    sensors @3 :List(SensorPoint);   # an analysis job's sensors in the lease's cell, measured there
  }
}

# What a job computes (common/job/job_settings.h). A Submit may leave
# automatic values (0, "", lightHops -2): the coordinator resolves them once
# (resolveJobSettings) and every Assign carries the complete spec.
struct JobSpec {
  store @0 :Text;          # scene store directory (absolute)
  output @1 :Text;         # image path (.png or .exr), absolute
  photons @2 :UInt64;
  spp @3 :UInt32;
  seed @4 :UInt64;
  accel @5 :Text;
  width @6 :UInt32;        # 0 (in a Submit): the camera's
  height @7 :UInt32;
  exposure @8 :Float32;
  lightSamples @9 :UInt32;
  photonK @10 :UInt32;     # photons per density estimate
  photonRadius @11 :Float32;  # largest density-estimate radius (metres)
  gather @12 :UInt32;      # final-gather rays per camera hit (0: estimate at the hit)
  aov @13 :Aov;            # what the image shows
  lightHops @14 :Int32 = 2;  # sample lights of cells within this many portals (-1: every light; -2: 2 for room cells, every light for voxel cells)
  irradiance @15 :Irradiance;  # what a final-gather hit reads
  renderAccel @16 :Text;   # accelerator of render leases ("" in a Submit: bvh with grid or auto, else accel)
  camera @17 :JobCamera;   # absent (in a Submit): the store's camera; always present once resolved
  # Progressive rendering (docs/architecture.md, "Render passes"): the render
  # phase runs passes of `spp` samples per pixel, each with its own seed,
  # until the error estimate reaches targetError, the next pass would end
  # past timeLimit, or maxPasses passes are done.
  targetError :union {
    none @18 :Void;
    value @19 :Float64;    # relative standard error of 16x16 blocks, as a fraction (0.02: 2 %)
  }
  timeLimit :union {
    none @20 :Void;
    seconds @21 :Float64;  # of render phase
  }
  maxPasses @22 :UInt32;   # 0 (in a Submit): 1 without a target or time limit, else kProgressiveMaxPasses
  cameraName @23 :Text;    # in a Submit: the store camera of this name ("": none); "" once resolved
  daylight @24 :Daylight;  # absent: no daylight
  analysis @25 :Analysis;  # present: a lighting analysis (illuminance at sensors), not an image
  luminance @26 :LuminanceImage;  # present: the image in cd/m^2 (--aov luminance), with its false-colour picture
  lightSampling @27 :LightSampling;  # how a shading point chooses a light (a spec from before the light tree reads as scan)
}

# A render's image in photometric units (common/job/job_settings.h
# LuminanceImage): 179 lm/W x Rec. 709 Y per pixel, a float image; with
# falseColor, OUTPUT.falsecolor.png beside it.
struct LuminanceImage {
  falseColor @0 :Bool;
  falseColorMaximum @1 :Float64;  # cd/m^2; 0: automatic
  falseColorDecades @2 :UInt32;   # 0: linear; N: logarithmic over N decades
  falseColorSteps @3 :UInt32;     # legend intervals
}

# A lighting analysis (docs/lighting-analysis.md): the job measures the
# illuminance at its sensors (sent in the Submit, kept by the coordinator)
# and writes a CSV to `output`. Its film is `height` = sensors rows of
# `width` = 2 x kSensorGroups columns (common/analysis/sensor_film.h).
struct Analysis {
  sensors @0 :UInt32;       # how many the Submit carries
  daylightFactor @1 :Bool;  # report DF = 100 E / E_out of the CIE overcast sky
}

# Sun and sky outside the building (common/job/job_settings.h DaylightSettings).
struct Daylight {
  sky @0 :SkyKind;
  skyR @1 :Float32;        # uniform sky's radiance
  skyG @2 :Float32;
  skyB @3 :Float32;
  turbidity @4 :Float32;
  sun @5 :Bool;
  sunAzimuth @6 :Float32;  # degrees from +Z towards +X
  sunElevation @7 :Float32;  # degrees above the horizon
  sunR @8 :Float32;        # sun's irradiance; all zero: the sun model's
  sunG @9 :Float32;
  sunB @10 :Float32;
  # In a Submit: the sun by date, time and place, which the coordinator
  # resolves into sunAzimuth and sunElevation; absent once resolved.
  sunTime @11 :SunTime;
}

# common/job/job_settings.h SunTime: each place value unset takes the
# store's site's.
struct SunTime {
  unixSeconds @0 :Int64;   # the instant, POSIX seconds (UTC)
  latitude :union {
    site @1 :Void;
    degrees @2 :Float64;   # north positive
  }
  longitude :union {
    site @3 :Void;
    degrees @4 :Float64;   # east positive
  }
  northAzimuth :union {
    site @5 :Void;
    degrees @6 :Float64;   # portico azimuth of geographic north
  }
}

enum SkyKind {
  none @0;
  uniform @1;
  preetham @2;
  overcast @3;
}

# A camera chosen at render time (common/job/job_settings.h JobCamera).
struct JobCamera {
  fromX @0 :Float32;
  fromY @1 :Float32;
  fromZ @2 :Float32;
  atX @3 :Float32;
  atY @4 :Float32;
  atZ @5 :Float32;
  upX @6 :Float32;         # up all zero (in a Submit): the store camera's
  upY @7 :Float32;
  upZ @8 :Float32;
  fovY @9 :Float32;        # full vertical angle, degrees; 0 (in a Submit): the store camera's
  cell @10 :UInt32;        # the cell containing the eye (set by the coordinator)
}

enum LightSampling {
  scan @0;                 # every candidate light weighed at each shading point
  tree @1;                 # one descent of a light tree over the candidates
}

enum Irradiance {
  precomputed @0;          # the nearest irradiance precomputed at a subset of the cell's photons
  knn @1;                  # the k-nearest-photon estimate at every gather hit
}

enum Aov {
  radiance @0;             # the rendered image
  cells @1;                # false colour: the cell of each camera ray's first visible hit
  portals @2;              # how many portals each camera ray crossed before its first visible hit
}

struct Counter {
  name @0 :Text;
  value @1 :Int64;
}

# Fixed-point radiance sums (see common/film.h): integer addition is
# associative, so the film does not depend on the order results arrive in.
struct PixelSum {
  pixel @0 :UInt32;
  r @1 :Int64;
  g @2 :Int64;
  b @3 :Int64;
}

struct CellRays {
  cell @0 :UInt32;
  rays @1 :List(Ray);
}

struct Hello {
  version @0 :UInt32;
  name @1 :Text;
  cores @2 :UInt32;
  memoryBytes @3 :UInt64;
  # Its pools (`portico-worker --tag`): a job that requires tags is leased
  # only to workers having all of them (common/job/worker_tags.h).
  tags @4 :List(Text);
}

# A worker's heartbeat says how far its leases have come, so that the
# coordinator can tell a worker whose tracing is stuck (a read that never
# returns) from one that traces: its heartbeats alone would hold its leases
# for good. The coordinator's heartbeats leave both 0.
struct Heartbeat {
  progress @0 :UInt64;      # grows as its leases move: rays traced, cells loaded, files and photons received, leases done
  tracingLease @1 :UInt64;  # the lease its tracing thread is in (0: none)
}

struct Welcome {
  version @0 :UInt32;
  heartbeatMs @1 :UInt32;
  maxFrameBytes @2 :UInt64;  # the largest frame the coordinator accepts; a bigger Result is sent as a Failure
}

struct Assign {
  lease @0 :UInt64;
  attempt @1 :UInt32;
  job @2 :UInt64;
  phase @3 :Phase;
  cell @4 :UInt32;
  spec @5 :JobSpec;        # in a render lease, seed is its render pass's (coordinator/render_passes.h)
  batches @6 :List(RayBatch);
  # The scheduler's work measure (rays held or to be generated): this lease's
  # batches, and everything the cell had pending in this phase when it was
  # leased (this lease included). `--accel auto` predicts a cell's rays from them.
  leaseWork @7 :Int64;
  cellWork @8 :Int64;
  # Photon pass only: more cells' batches in the same lease, cells the worker
  # likely holds, traced after `cell`'s (leaseWork counts them). At the end
  # of a pass each cell holds a few photons; one lease for several of them
  # is one round trip and one Result instead of one each.
  moreCells @9 :List(CellBatches);
  # The job whose photon tables a render lease reads: the lease's own job,
  # or the earlier job whose finished photon pass it reuses (same store,
  # same photon settings). Workers cache photon maps under it, so a reused
  # pass reuses their cached maps too.
  photonJob @10 :UInt64;
  # Photon pass, when the job's photon file allows it: where the worker may
  # write this lease's deposits (see DepositRegion); absent otherwise.
  depositRegion @11 :DepositRegion;
}

struct CellBatches {
  cell @0 :UInt32;
  batches @1 :List(RayBatch);
}

struct Result {
  lease @0 :UInt64;
  counters @1 :List(Counter);
  crossings @2 :List(CellRays);
  deposits @3 :List(CellPhotons);
  film @4 :List(PixelSum);
  # The nonce read from the lease's deposit region, when some deposits were
  # written there (their CellPhotons carry fileSize > 0); empty otherwise.
  regionNonce @5 :Data;
}

struct Failure {
  lease @0 :UInt64;
  message @1 :Text;
  # The cell whose work failed, when it is one of the lease's moreCells
  # (the default: the lease's own cell).
  failedCell @2 :UInt32 = 0xffffffff;
}

struct FetchPhotons {
  job @0 :UInt64;           # the lease's job; the coordinator serves the tables of its photonJob
  cell @1 :UInt32;
  # The worker reads the job's photon file itself where it can (a shared
  # file system): the reply may name where the batches lie (PhotonsReply.file)
  # instead of carrying them. False (older workers, and a worker that could
  # not read what a reply named): the bytes come in the reply.
  readsPhotonFile @2 :Bool;
}

# Where one photon batch lies in the job's photon file, and its CRC-32C.
struct FileExtent {
  offset @0 :UInt64;
  size @1 :UInt64;
  crc @2 :UInt32;
}

struct PhotonsReply {
  job @0 :UInt64;
  cell @1 :UInt32;
  batches @2 :List(Data);   # the cell's photon table: 8-byte records, batch by batch
  error @3 :Text;           # non-empty: the table could not be read (no batches); the lease is failed, nothing cached
  # To a worker that reads the photon file itself (FetchPhotons.readsPhotonFile):
  # the file (absolute) and the batches' places in it, in order, instead of
  # `batches`. One it cannot read, or whose bytes fail their CRC, it asks
  # for again, bytes included.
  file @4 :Text;
  extents @5 :List(FileExtent);
}

# Cells over the wire: a worker without the scene store's file system asks
# for its files (scene.db, cells/N.cell) chunk by chunk and keeps them in its
# disk cache (worker --cache-dir).
struct FetchFile {
  store @0 :Text;           # the store directory as the job names it
  path @1 :Text;            # "scene.db" or "cells/<id>.cell"
  offset @2 :UInt64;
}

struct FileChunk {
  store @0 :Text;
  path @1 :Text;
  offset @2 :UInt64;
  totalBytes @3 :UInt64;    # the whole file's size
  data @4 :Data;            # at most 4 MiB from offset
  error @5 :Text;           # empty on success; else why the file cannot be served
}

struct Submit {
  spec @0 :JobSpec;
  # A photon pass of its own, even when an earlier job's finished pass on
  # the same store with the same photon settings could be reused.
  freshPhotons @1 :Bool;
  # An analysis job's sensors (spec.analysis), in the sensor file's order.
  sensors @2 :List(SensorPoint);
  # Scheduling, which never changes what the job computes: its leases come
  # before those of lower priorities (kMinPriority..kMaxPriority,
  # coordinator/job_limits.h; equal priorities: the older job first), and
  # go only to workers having every tag of requiredTags.
  priority @3 :Int32;
  requiredTags @4 :List(Text);
}

struct SubmitReply {
  job @0 :UInt64;
  error @1 :Text;           # empty on success
}

struct StatusRequest {
  job @0 :UInt64;           # 0: all jobs
}

struct StatusReply {
  json @0 :Text;            # one JSON object (see coordinator/status.cpp)
}

struct CancelRequest {
  job @0 :UInt64;
}

# A job's new priority (as Submit.priority), from its next lease on: the
# leases in flight finish. Answered with the job's StatusReply, as Cancel.
struct PriorityRequest {
  job @0 :UInt64;
  priority @1 :Int32;
}

# A finished job's image, encoded as its output's extension says (.png,
# .exr, ...), for the client to write itself (`portico fetch-image`).
struct FetchImage {
  job @0 :UInt64;
}

struct ImageReply {
  job @0 :UInt64;
  output @1 :Text;          # the path the job was submitted with (its extension decides the format)
  image @2 :Data;           # the encoded file
  statistics @3 :Text;      # what the coordinator writes beside the image as OUTPUT.json
  error @4 :Text;           # non-empty: no image (the job is not done, or it cannot be encoded)
}

# What `portico dashboard` shows of a job beyond its status: its cells'
# state (queued, leased and to which worker, done) and loads, and its recent
# log lines.
struct JobDetailRequest {
  job @0 :UInt64;
}

struct JobDetailReply {
  # {"job", "phase", "cells": [{"cell", "pending", "leased_by", "done", "loads"}], "log": [lines]}
  # (coordinator/job_activity.h)
  json @0 :Text;
}

# A job's film so far (render phase, or done), averaged over the passes done
# and box-filtered down to at most maxSide pixels on its longer side: linear
# radiance the dashboard tone-maps with the exposure its viewer picks.
struct FetchPreview {
  job @0 :UInt64;
  maxSide @1 :UInt32;      # 0: the film's own size (at most 1024 either way)
}

struct PreviewReply {
  job @0 :UInt64;
  width @1 :UInt32;
  height @2 :UInt32;
  rgb @3 :Data;            # width * height * 3 little-endian float32, row 0 at the top
  exposure @4 :Float32;    # the job's --exposure
  cameraRaysDone @5 :Int64;  # what the film holds so far: a new value, a new image
  error @6 :Text;          # non-empty: no film yet (photon pass, analysis, unknown job)
}

struct Envelope {
  union {
    hello @0 :Hello;
    welcome @1 :Welcome;
    heartbeat @2 :Heartbeat;
    ready @3 :Void;
    assign @4 :Assign;
    result @5 :Result;
    failure @6 :Failure;
    fetchPhotons @7 :FetchPhotons;
    photons @8 :PhotonsReply;
    submit @9 :Submit;
    submitReply @10 :SubmitReply;
    status @11 :StatusRequest;
    statusReply @12 :StatusReply;
    cancel @13 :CancelRequest;
    shutdown @14 :Void;
    error @15 :Text;         # a request the coordinator refused
    goodbye @16 :Void;       # a worker leaving cleanly
    fetchFile @17 :FetchFile;
    fileChunk @18 :FileChunk;
    fetchImage @19 :FetchImage;
    image @20 :ImageReply;
    jobDetail @21 :JobDetailRequest;
    fetchPreview @22 :FetchPreview;
    preview @23 :PreviewReply;
    jobDetailReply @24 :JobDetailReply;
    priority @25 :PriorityRequest;
  }
}
