#!/usr/bin/env bash
# deploy/local: `portico-local start` with two workers, `portico submit` and
# `portico wait` against it (the commands of docs/deploy.md), the image equal
# bit for bit to `portico render`'s, `portico-local stop`, and no process left.
#   local_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
source "$source_dir/tests/deploy/lib.sh"
export PATH="$bin:$PATH"
portico_local="$source_dir/deploy/local/portico-local"

tmp=$(mktemp -d /tmp/portico-local-test.XXXXXX)
state="$tmp/state"
cleanup() {
  local code=$?
  "$portico_local" stop --state-dir "$state" --timeout 5 > /dev/null 2>&1 || true
  if [ $code -ne 0 ]; then
    for f in "$state"/*.log; do [ -e "$f" ] && { echo "--- $f"; tail -n 30 "$f"; }; done
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
cd "$tmp"

log "scene and reference render"
portico scene generate --preset demo building > /dev/null
portico render building -o reference.exr "${deploy_render_options[@]}" --workers 1 > /dev/null 2>&1

log "sizing (docs/deploy.md, Sizing workers)"
portico scene info --json building | python3 -c '
import json, sys
s = json.load(sys.stdin)
c = max(s["cell_list"], key=lambda c: c["bytes"])
print("%d cells, max_triangles_per_cell %d; largest cell %s: %d triangles, %d bytes (%.1f MiB)"
      % (s["cells"], s["max_triangles_per_cell"], c["name"], c["triangles"], c["bytes"], c["bytes"] / 2**20))' \
  | tee sizing.out
grep -Eq '^[0-9]+ cells, max_triangles_per_cell [0-9]+; largest cell .+: [0-9]+ triangles, [0-9]+ bytes' sizing.out \
  || fail "the sizing command of docs/deploy.md printed: $(cat sizing.out)"

log "portico-local start"
# As in docs/deploy.md, with a free port (*) and this test's own state folder; the
# workers in pools bigmem and gpu (--tags), which the job below requires.
"$portico_local" start --workers 2 --state-dir "$state" --listen 'tcp://127.0.0.1:*' --tags bigmem,gpu | tee start.out
endpoint=$("$portico_local" endpoint --state-dir "$state")
grep -qx "endpoint: $endpoint" start.out || fail "start did not print the endpoint $endpoint"
grep -q "worker 1: .*log $state/worker-1.log" start.out || fail "start did not print the workers' logs"
"$portico_local" status --state-dir "$state" | tee status.out
[ "$(grep -c ': running' status.out)" = 3 ] || fail "status does not show 3 running services"
# A second start on the same state folder refuses.
if "$portico_local" start --workers 1 --state-dir "$state" --listen 'tcp://127.0.0.1:*' 2> second.err; then
  fail "a second start on a running state folder succeeded"
fi
grep -q "already running" second.err || fail "second start: $(cat second.err)"

log "portico submit / wait against $endpoint"
job=$(portico submit --coordinator "$endpoint" building -o image.exr "${deploy_render_options[@]}" --require bigmem)
portico wait --coordinator "$endpoint" "$job"
expect_same_pixels image.exr reference.exr
# Both workers are connected (the job status lists the coordinator's workers).
portico status --coordinator "$endpoint" "$job" --json > status.json
for i in 0 1; do grep -q "\"local-$i\"" status.json || fail "worker local-$i not in the job status"; done
python3 -c '
import json, sys
workers = json.load(open("status.json"))["workers"]
tags = sorted(tuple(w["tags"]) for w in workers)
sys.exit(0 if tags == [("bigmem", "gpu")] * 2 else "workers tagged %s, not bigmem and gpu" % tags)' \
  || fail "portico-local --tags did not reach the workers"
# PORTICO_WORKER_TAGS, as the systemd, Kubernetes, Slurm and Docker templates set it.
PORTICO_WORKER_TAGS="big.mem, spare" portico-worker --connect "$endpoint" --name env-tagged --memory 256MiB \
  > env-worker.log 2>&1 &
env_worker=$!
for _ in $(seq 50); do
  portico status --coordinator "$endpoint" --json > farm.json
  grep -q '"env-tagged"' farm.json && break
  sleep 0.1
done
kill "$env_worker"; wait "$env_worker" || true
python3 -c '
import json, sys
tags = [w["tags"] for w in json.load(open("farm.json"))["workers"] if w["name"] == "env-tagged"]
sys.exit(0 if tags == [["big.mem", "spare"]] else "env-tagged worker has tags %s" % tags)' \
  || fail "PORTICO_WORKER_TAGS did not reach the worker: $(cat env-worker.log)"


pids=$(cat "$state"/*.pid)
log "portico-local stop"
"$portico_local" stop --state-dir "$state" | tee stop.out
[ "$(grep -c '^stopped' stop.out)" = 3 ] || fail "stop did not stop 3 services"
grep -q SIGKILL stop.out && fail "a service needed SIGKILL"
for pid in $pids; do alive "$pid" && fail "pid $pid still alive after stop"; done
left=$(processes_with "$state"; processes_with "$endpoint")
[ -z "$left" ] || fail "processes left after stop: $left"
ls "$state"/*.pid > /dev/null 2>&1 && fail "pid files left after stop"
if "$portico_local" status --state-dir "$state"; then fail "status after stop reports something running"; fi

log "stop escalates to SIGKILL for a service that does not end on SIGTERM"
"$portico_local" start --workers 1 --state-dir "$state" --listen 'tcp://127.0.0.1:*' > /dev/null
stuck=$(cat "$state/worker-0.pid")
kill -STOP "$stuck"   # a stopped process does not act on SIGTERM until it is continued
"$portico_local" stop --state-dir "$state" --timeout 1 2>&1 | tee stop.out
grep -q "worker-0 (pid $stuck) did not stop within 1 s; sending SIGKILL" stop.out || fail "no SIGKILL for a stuck worker"
alive "$stuck" && fail "the stuck worker $stuck is still alive"
left=$(processes_with "$state")
[ -z "$left" ] || fail "processes left after stop: $left"
log "PASS"
