#!/usr/bin/env bash
# CPU seconds of the coordinator and of the workers during one job's photon
# phase, read from /proc when the coordinator logs the phase's end
# (docs/pipeline-benchmark.md, "Where the time goes now").
#
#   tests/bench/photon_phase_cpu.sh BIN_DIR STORE WORKERS PHOTONS [RUNS]
#
# BIN_DIR: portico, portico-coordinator and portico-worker (e.g. build/bin).
# COORDINATOR=PATH runs another coordinator binary (an A/B of two builds);
# ACCEL=SPEC another accelerator than grid.
# Also printed: the machine's idle core-seconds over the phase (/proc/stat),
# and the coordinator's CPU over the workers' (which cancels the VM's drift).
# STORE: a scene store (e.g. the one `portico bench pipeline --store DIR` keeps).
set -euo pipefail
bin=${1:?usage: photon_phase_cpu.sh BIN_DIR STORE WORKERS PHOTONS [RUNS]}
store=${2:?usage: photon_phase_cpu.sh BIN_DIR STORE WORKERS PHOTONS [RUNS]}
workers=${3:?usage: photon_phase_cpu.sh BIN_DIR STORE WORKERS PHOTONS [RUNS]}
photons=${4:?usage: photon_phase_cpu.sh BIN_DIR STORE WORKERS PHOTONS [RUNS]}
runs=${5:-1}
ticks=$(getconf CLK_TCK)

idle() { awk '/^cpu /{print $5 + $6}' /proc/stat; }   # idle + iowait ticks, all cores
cpu() {   # CPU ticks (user + system) of the given processes, all threads
  local total=0
  for p in "$@"; do total=$((total + $(awk '{print $14 + $15}' "/proc/$p/stat"))); done
  echo "$total"
}

for run in $(seq "$runs"); do
  work=$(mktemp -d /tmp/portico-phase-cpu-XXXXXX)
  "${COORDINATOR:-$bin/portico-coordinator}" --listen "ipc://$work/coordinator.sock" --db "$work/jobs.db" --endpoint-file "$work/endpoint" \
    --log-level info > "$work/coordinator.log" 2>&1 &
  coordinator=$!
  for _ in $(seq 200); do [[ -s "$work/endpoint" ]] && break; sleep 0.05; done
  endpoint=$(cat "$work/endpoint")
  pids=()
  for i in $(seq "$workers"); do
    "$bin/portico-worker" --connect "$endpoint" --memory 4GiB --name "w$i" --log-level warn > /dev/null 2>&1 &
    pids+=($!)
  done
  sleep 0.5
  c0=$(cpu "$coordinator"); w0=$(cpu "${pids[@]}"); t0=$(date +%s.%N); i0=$(idle)
  "$bin/portico" submit "$store" --coordinator "$endpoint" -o "$work/x.exr" --photons "$photons" --spp 1 \
    --gather 0 --width 8 --height 8 --accel "${ACCEL:-grid}" > /dev/null
  until grep -q "photon phase done" "$work/coordinator.log"; do sleep 0.02; done
  c1=$(cpu "$coordinator"); w1=$(cpu "${pids[@]}"); t1=$(date +%s.%N); i1=$(idle)
  python3 -c "c, w = ($c1 - $c0) / $ticks, ($w1 - $w0) / $ticks; print('workers %s  photon phase %.2f s  coordinator %.2f CPU-s  workers %.2f CPU-s  coordinator/workers %.3f  idle %.2f core-s' % ('$workers', $t1 - $t0, c, w, c / w, ($i1 - $i0) / $ticks))"
  kill "$coordinator" "${pids[@]}" 2> /dev/null || true
  wait 2> /dev/null || true
  rm -rf "$work"
done
