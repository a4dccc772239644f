#!/usr/bin/env bash
# Across hosts, for real: the coordinator in one network namespace and three
# workers in three others, each joined to the coordinator's by its own veth
# pair shaped like a network link, 2 ms delay and 100 Mbit/s each way (tc
# netem; on a kernel without netem, tbf for the rate and a relay in the
# worker's namespace, delay_relay.py, for the delay), over tcp:// with CURVE
# keys as beyond loopback. The workers share no file
# system with the coordinator: each runs in a mount namespace where the
# coordinator's folder (store, jobs.db, photon files) is an empty tmpfs, with
# its own --cache-dir, so cells come over the wire and deposits go in
# Results. A 2-floor building renders bit-identical to `portico render`'s
# local run; then a second job (its own photon pass) has one worker's link
# cut while that worker holds a lease, and still finishes bit-identical, its
# lease taken back and traced by the others.
# Skips (77) where it cannot make namespaces (not root, no `ip netns`).
# Usage: netns_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin=$1
source "$(dirname "$0")/lib.sh"

skip() { echo "SKIP: $*"; exit "$DEPLOY_SKIP"; }
[ "$(id -u)" = 0 ] || skip "network namespaces need root (this is uid $(id -u))"
command -v ip > /dev/null && command -v tc > /dev/null ||
  skip "ip and tc (iproute2) are missing: deploy/install-deps.sh installs them"
command -v unshare > /dev/null || skip "unshare (util-linux) is missing"

work=$(mktemp -d /tmp/portico-netns-XXXXXX)
prefix="pn$$"   # namespace names unique to this run
coord_ns="${prefix}c"
worker_ns=("${prefix}w0" "${prefix}w1" "${prefix}w2")
pids=()
cleanup() {
  local status=$?
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2> /dev/null || true; done
  for ns in "$coord_ns" "${worker_ns[@]}"; do ip netns del "$ns" 2> /dev/null || true; done
  if [ "$status" -ne 0 ] && [ "$status" -ne "$DEPLOY_SKIP" ]; then
    for log in "$work"/*.log; do [ -f "$log" ] && { echo "--- $log"; tail -25 "$log"; }; done
  fi
  rm -rf "$work"
}
trap cleanup EXIT

ip netns add "$coord_ns" 2> "$work/netns.err" || skip "cannot make a network namespace: $(cat "$work/netns.err")"
unshare --mount --propagation private sh -c 'mount -t tmpfs tmpfs "$1"' sh "$work" 2> "$work/mount.err" ||
  skip "cannot make a mount namespace with a tmpfs (the workers' file system): $(cat "$work/mount.err")"
for ns in "${worker_ns[@]}"; do ip netns add "$ns"; done
ip -n "$coord_ns" link set lo up

# The link's shape on one end of a veth: delay and rate with netem, else the
# rate alone (and the delay from a relay, below).
netem=yes
shape() {   # NS DEVICE
  if ! tc -n "$1" qdisc add dev "$2" root netem delay 2ms rate 100mbit 2> /dev/null; then
    tc -n "$1" qdisc add dev "$2" root tbf rate 100mbit burst 64kb latency 50ms
    netem=""
  fi
}
for i in 0 1 2; do
  ns=${worker_ns[$i]}
  ip link add name "v${i}c" netns "$coord_ns" type veth peer name "v${i}w" netns "$ns"
  ip -n "$coord_ns" addr add "10.77.$i.1/24" dev "v${i}c"
  ip -n "$ns" addr add "10.77.$i.2/24" dev "v${i}w"
  for end in "$coord_ns v${i}c" "$ns v${i}w"; do
    read -r n dev <<< "$end"
    ip -n "$n" link set "$dev" up
    shape "$n" "$dev"
  done
  ip -n "$ns" link set lo up
done
if [ -n "$netem" ]; then shaping="tc netem delay 2ms rate 100mbit"
else shaping="tc tbf rate 100mbit; this kernel has no netem: the 2 ms delay each way from delay_relay.py"; fi
log "namespaces: coordinator $coord_ns, workers ${worker_ns[*]}; links: $shaping"
# The coordinator's folder, which no worker sees.
job_dir="$work/coordinator"
mkdir -p "$job_dir"
"$bin/portico" scene generate --preset l-shape "$job_dir/building" > "$work/generate.log" 2>&1
"$bin/portico" keys generate "$work/keys" > /dev/null
options=(--photons 300000 --spp 4 --gather 2 --width 160 --height 120 --seed 7)
log "reference: portico render with one local worker"
"$bin/portico" render "$job_dir/building" -o "$work/reference.exr" "${options[@]}" --workers 1 > "$work/reference.log" 2>&1

port=5555
ip netns exec "$coord_ns" "$bin/portico-coordinator" --listen "tcp://0.0.0.0:$port" --keys "$work/keys" \
  --db "$job_dir/jobs.db" --heartbeat-ms 500 --liveness-ms 3000 > "$work/coordinator.log" 2>&1 &
pids+=($!)
endpoint="tcp://127.0.0.1:$port"
# TCP connects from a worker's namespace: to its own link's address, and to another worker's.
connects() {   # NS ADDRESS
  ip netns exec "$1" python3 -c 'import socket, sys
try:
    socket.create_connection((sys.argv[1], int(sys.argv[2])), timeout=2).close()
except OSError:
    sys.exit(1)' "$2" "$port"
}
for _ in $(seq 100); do connects "${worker_ns[0]}" 10.77.0.1 && break; sleep 0.1; done
connects "${worker_ns[0]}" 10.77.0.1 || fail "${worker_ns[0]} cannot reach the coordinator at 10.77.0.1:$port"
! connects "${worker_ns[1]}" 10.77.0.1 ||
  fail "${worker_ns[1]} reaches the coordinator through worker 0's link: the namespaces are not separate"
client() { ip netns exec "$coord_ns" "$bin/portico" "$@" --coordinator "$endpoint" --keys "$work/keys"; }

# Where each worker connects: the coordinator across its link, or (no
# netem) the relay in its namespace that delays what crosses the link.
worker_endpoint=()
for i in 0 1 2; do
  if [ -n "$netem" ]; then
    worker_endpoint+=("tcp://10.77.$i.1:$port")
  else
    ip netns exec "${worker_ns[$i]}" python3 "$(dirname "$0")/delay_relay.py" 127.0.0.1 "$port" "10.77.$i.1" "$port" 2 \
      > "$work/relay-$i.log" 2>&1 &
    pids+=($!)
    worker_endpoint+=("tcp://127.0.0.1:$port")
  fi
done
# The time to the coordinator's first bytes (its ZMTP greeting, sent as a
# connection opens) from worker 0's namespace, by the path its worker
# takes: at least the link's one-way 2 ms.
greeting_ms() {
  ip netns exec "${worker_ns[0]}" python3 -c 'import socket, sys, time
host, port = sys.argv[1].removeprefix("tcp://").rsplit(":", 1)
started = time.monotonic()
with socket.create_connection((host, int(port)), timeout=5) as s:
    s.recv(1)
print(f"{(time.monotonic() - started) * 1000:.2f}")' "$1"
}
for _ in $(seq 100); do greeting_ms "${worker_endpoint[0]}" > /dev/null 2>&1 && break; sleep 0.1; done
delay=$(greeting_ms "${worker_endpoint[0]}") || fail "no greeting from the coordinator through ${worker_endpoint[0]}"
python3 -c 'import sys; sys.exit(0 if float(sys.argv[1]) >= 2.0 else 1)' "$delay" ||
  fail "the coordinator's greeting came after $delay ms: the link has no 2 ms delay"
log "the coordinator's greeting reaches worker 0's namespace after $delay ms"

for i in 0 1 2; do
  # Its own mount namespace, the coordinator's folder covered by an empty tmpfs.
  ip netns exec "${worker_ns[$i]}" unshare --mount --propagation private sh -c \
    'mount -t tmpfs tmpfs "$1" && shift && exec "$@"' sh "$job_dir" \
    "$bin/portico-worker" --connect "${worker_endpoint[$i]}" --keys "$work/keys" --cache-dir "$work/cache-$i" \
    --memory 1GiB --name "ns-worker-$i" > "$work/worker-$i.log" 2>&1 &
  pids+=($!)
done

# Waits until COUNT workers have joined.
wait_for_workers() {
  for _ in $(seq 300); do
    n=$(client status --json 2> /dev/null | python3 -c 'import json,sys; print(len(json.load(sys.stdin).get("workers", [])))' ||
      echo 0)
    [ "$n" -ge "$1" ] && return 0
    sleep 0.1
  done
  fail "$1 workers did not join within 30 s"
}
wait_for_workers 3

log "job 1: three workers across namespaces"
job=$(client submit "$job_dir/building" -o "$job_dir/image-1.exr" "${options[@]}")
client wait "$job" --timeout 120 > /dev/null || fail "job $job did not finish: $(client status "$job")"
expect_same_pixels "$job_dir/image-1.exr" "$work/reference.exr"
for i in 0 1 2; do
  [ -s "$work/cache-$i/"*/scene.db ] 2> /dev/null || fail "worker $i fetched no scene.db into its --cache-dir"
done
python3 - "$job_dir/image-1.exr.json" <<'PY' || fail "the workers wrote deposits into the coordinator's files"
import json, sys
disk = json.load(open(sys.argv[1]))["disk"]
assert disk["photon_bytes_from_workers"] == 0 and disk["photon_bytes_from_results"] > 0, disk
print(f"deposits all in Results: {disk['photon_bytes_from_results']} bytes")
PY

log "job 2: its own photon pass; worker 0's link cut while it holds a lease"
job=$(client submit "$job_dir/building" -o "$job_dir/image-2.exr" "${options[@]}" --fresh-photons)
cut=""
for _ in $(seq 600); do
  if client status "$job" --json 2> /dev/null | python3 -c '
import json, sys
s = json.load(sys.stdin)
w = [w for w in s.get("workers", []) if w["name"] == "ns-worker-0"]
sys.exit(0 if w and w[0]["leases_in_flight"] and w[0]["leases_done"] >= 2 else 1)'; then
    ip -n "${worker_ns[0]}" link set v0w down
    cut=yes
    break
  fi
  sleep 0.05
done
[ -n "$cut" ] || fail "worker 0 never held a lease of job $job"
log "cut worker 0's link"
client wait "$job" --timeout 120 > /dev/null || fail "job $job did not finish after the cut: $(client status "$job")"
grep -q "requeued: worker ns-worker-0" "$work/coordinator.log" ||
  fail "the coordinator did not take back worker 0's lease (coordinator.log)"
grep "requeued: worker ns-worker-0" "$work/coordinator.log" | head -2
expect_same_pixels "$job_dir/image-2.exr" "$work/reference.exr"
echo "PASS"
