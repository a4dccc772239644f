#!/bin/bash
# same_bits.sh OLD_BIN NEW_BIN [WORK_DIR]: do two builds render the same?
#
# For a change that must not alter any result (a refactoring): renders every
# generated preset (small images, 100 000 photons; the tower with 2 floors)
# and both reference scenes of tests/scenes (default settings, 2 workers and
# 1 worker) with the programs of OLD_BIN and of NEW_BIN, then compares the
# pixels exactly (oiiotool --diff with zero tolerance: EXR headers carry the
# write time, so file hashes differ anyway) and the job's counters that do
# not depend on scheduling (photons, rays, film; not leases, loads, maps
# built, rays forwarded between held cells, memory peaks or the bytes each
# way photons took to and from the files). Exit status 0: all the same.
# Takes about 2 minutes on 2 cores.
set -euo pipefail
old_bin=$(realpath "$1"); new_bin=$(realpath "$2")
work=${3:-$(mktemp -d /tmp/portico-same-bits.XXXXXX)}
scenes=$(realpath "$(dirname "$0")/../scenes")
mkdir -p "$work"

# counters JOBS_DB OUT: the scheduling-independent counters of job 1.
counters() {
  sqlite3 "$1" "select name, value from counters where job = 1
    and name not like 'time.%' and name not like 'cells.%' and name not like 'accel.%' and name not like 'leases.%'
    and name not like 'memory.%' and name not like 'disk.%'
    and name not in ('irradiance.points', 'photon_maps.built', 'rays.forwarded') order by name" > "$2"
}

# render_with BIN OUT_DIR NAME STORE ARGS...: one image and its counters.
render_with() {
  local bin=$1 out=$2 name=$3 store=$4; shift 4
  local log="$out/$name.log"
  "$bin/portico" render "$store" -o "$out/$name.exr" --keep-logs "$@" > "$log" 2>&1
  local logs; logs=$(sed -n 's/^logs and jobs.db kept in //p' "$log")
  counters "$logs/jobs.db" "$out/$name.counters"
  rm -rf "$logs"
}

for side in old new; do
  bin=$old_bin; [ "$side" = new ] && bin=$new_bin
  out="$work/$side"; mkdir -p "$out"
  for preset in demo l-shape z-building octagon soda-hall tower; do
    floors=(); [ "$preset" = tower ] && floors=(--floors 2)
    rm -rf "$work/store"
    "$bin/portico" scene generate --preset "$preset" "${floors[@]}" "$work/store" > /dev/null
    render_with "$bin" "$out" "$preset" "$work/store" --photons 100000 --spp 2 --width 160 --height 120
  done
  for scene in cornell_closed two_rooms; do
    rm -rf "$work/store"
    "$bin/portico" scene import "$scenes/$scene/scene.json" "$work/store" > /dev/null
    render_with "$bin" "$out" "$scene" "$work/store"
    render_with "$bin" "$out" "$scene-1w" "$work/store" --workers 1
  done
  rm -rf "$work/store"
done

status=0
for image in "$work"/old/*.exr; do
  name=$(basename "$image" .exr)
  if oiiotool "$image" "$work/new/$name.exr" --fail 0 --failpercent 0 --warn 0 --diff > /dev/null 2>&1; then
    pixels="same pixels"
  else
    pixels="DIFFERENT PIXELS"; status=1
  fi
  if cmp -s "$work/old/$name.counters" "$work/new/$name.counters"; then
    counts="same counters"
  else
    counts="DIFFERENT COUNTERS"; status=1
  fi
  printf '%-16s %-18s %s\n' "$name" "$pixels" "$counts"
done
[ $status = 0 ] && echo "same bits: every image and counter" || echo "differences: see $work/{old,new}"
exit $status
