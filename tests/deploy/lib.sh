# shellcheck shell=bash disable=SC2034   # the variables are for the tests that source this file
# Shared by the deploy tests (sourced): the small render they all make, and helpers.

# A small, fast render: the demo building at 96x64 with few photons and samples.
deploy_render_options=(--photons 20000 --spp 2 --gather 2 --width 96 --height 64 --seed 7)

# ctest's skip code (SKIP_RETURN_CODE in tests/deploy/CMakeLists.txt).
DEPLOY_SKIP=77

log() { echo "[$(date +%H:%M:%S)] $*"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

# The SHA-1 of an image's pixels (OpenImageIO's iinfo): EXR headers carry the
# write time, so files of identical pixels differ; their pixel hashes do not.
pixel_hash() {
  iinfo --hash "$1" | sed -n 's/^ *SHA-1: *//p'
}

# Fails unless IMAGE's pixels are bit-identical to REFERENCE's.
expect_same_pixels() {
  local image=$1 reference=$2 a b
  [ -s "$image" ] || fail "no image at $image"
  [ -s "$image.json" ] || fail "no statistics at $image.json"
  a=$(pixel_hash "$image"); b=$(pixel_hash "$reference")
  [ -n "$a" ] && [ -n "$b" ] || fail "cannot hash $image or $reference (iinfo --hash)"
  [ "$a" = "$b" ] || fail "$image differs from $reference (pixel SHA-1 $a vs $b)"
  log "bit-identical pixels: $image = $reference (SHA-1 $a)"
}

# N free TCP ports on 127.0.0.1, one a line.
free_ports() {
  python3 - "$1" <<'PY'
import socket, sys
socks = []
for _ in range(int(sys.argv[1])):
    s = socket.socket(); s.bind(("127.0.0.1", 0)); socks.append(s)
print("\n".join(str(s.getsockname()[1]) for s in socks))
PY
}

# Pids of the processes (one a line) whose command line contains STRING: what is
# left of a test's services (give it the test's unique state folder or endpoint).
processes_with() {
  local needle=$1 p command
  for p in /proc/[0-9]*; do
    [ "${p#/proc/}" != "$$" ] || continue
    command=$(tr '\0' ' ' 2>/dev/null < "$p/cmdline") || continue
    [[ "$command" == *"$needle"* ]] && echo "${p#/proc/}"
  done
  return 0
}

# True when PID runs (a zombie, exited but not yet reaped by its parent, does not).
alive() {
  local state
  state=$(sed -n 's/^State:[[:space:]]*\([A-Z]\).*/\1/p' "/proc/$1/status" 2>/dev/null) || return 1
  [ -n "$state" ] && [ "$state" != Z ] && [ "$state" != X ]
}
