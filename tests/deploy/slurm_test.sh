#!/usr/bin/env bash
# deploy/slurm: a one-node Slurm cluster on localhost, started by hand (no
# systemd): munged, slurmctld and slurmd with their key, state, spool and logs
# under a temporary folder. Submits deploy/slurm/portico.sbatch for the demo
# building with two workers (two tasks) and checks the image is bit-identical
# to `portico render` with the same seed. Installs slurm-wlm through
# `deploy/install-deps.sh --slurm` where it is missing; skips (exit 77) only
# where that fails. Stops every daemon and job it started.
#   slurm_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
source "$source_dir/tests/deploy/lib.sh"
export PATH="$bin:$PATH"

# --- Slurm and MUNGE, installed where missing -----------------------------------
missing=()
for program in slurmctld slurmd sbatch srun scontrol munged; do
  command -v "$program" > /dev/null || [ -x "/usr/sbin/$program" ] || missing+=("$program")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "missing ${missing[*]}: deploy/install-deps.sh --slurm"
  if ! bash "$source_dir/deploy/install-deps.sh" --slurm; then
    echo "SKIP: slurm-wlm cannot be installed here (deploy/install-deps.sh --slurm failed)"
    exit $DEPLOY_SKIP
  fi
fi
export PATH="$PATH:/usr/sbin:/sbin"

tmp=$(mktemp -d /tmp/portico-slurm-test.XXXXXX)
chmod 755 "$tmp"
munge_pid="" slurmctld_pid="" slurmd_pid=""

stop_pid() {   # SIGTERM, up to 10 s, then SIGKILL
  local pid=$1
  [ -n "$pid" ] && alive "$pid" || return 0
  kill -TERM "$pid" 2>/dev/null || true
  for _ in $(seq 100); do alive "$pid" || return 0; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null || true
}
cleanup() {
  local code=$? pid
  set +e
  if [ -n "$slurmctld_pid" ] && alive "$slurmctld_pid"; then
    # Jobs first, while slurmd can still signal their steps; then whatever of
    # their processes is still there (linuxproc tracks them for listpids).
    scancel --full "--name=portico-test" > /dev/null 2>&1
    for _ in $(seq 50); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
  fi
  if [ -n "$slurmd_pid" ] && alive "$slurmd_pid"; then
    for pid in $(scontrol listpids 2>/dev/null | awk 'NR > 1 { print $1 }'); do stop_pid "$pid"; done
  fi
  stop_pid "$slurmd_pid"
  stop_pid "$slurmctld_pid"
  stop_pid "$munge_pid"
  # Anything still running from this test's folder (a step daemon, a worker).
  for pid in $(processes_with "$tmp"); do stop_pid "$pid"; done
  if [ $code -ne 0 ]; then
    for f in "$tmp"/log/*.log "$tmp"/submit/*.out "$tmp"/submit/portico-*/*.log; do
      [ -e "$f" ] && { echo "--- $f"; tail -n 40 "$f"; }
    done
  fi
  rm -rf "$tmp"
  exit $code
}
trap cleanup EXIT
trap 'exit 130' INT TERM

mkdir -p "$tmp"/{munge,state,spool,log,run,submit}
chmod 700 "$tmp/munge"
node=$(hostname -s)
cpus=$(nproc)
memory_mib=$(awk '/^MemTotal:/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)
read -r ctld_port slurmd_port < <(free_ports 2 | paste -sd ' ')
user=$(id -un)

# --- munged with its own key and socket -----------------------------------------
log "munged"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$tmp/munge/munge.key"
socket="$tmp/munge/munge.socket"
munged --foreground --force --socket="$socket" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
  --log-file="$tmp/log/munged.log" > "$tmp/log/munged.out.log" 2>&1 &
munge_pid=$!
for _ in $(seq 100); do [ -S "$socket" ] && break; alive "$munge_pid" || break; sleep 0.1; done
munge --socket="$socket" -n < /dev/null | unmunge --socket="$socket" > /dev/null \
  || fail "munged does not answer on $socket"

# --- slurm.conf for this machine ------------------------------------------------
export SLURM_CONF="$tmp/slurm.conf"
cat > "$SLURM_CONF" <<CONF
ClusterName=portico-test
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=60
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mib State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF

# --- slurmctld and slurmd in the foreground, in the background ------------------
log "slurmctld and slurmd on $node (ports $ctld_port, $slurmd_port)"
slurmctld -D -c -i -f "$SLURM_CONF" > "$tmp/log/slurmctld.out.log" 2>&1 &
slurmctld_pid=$!
for _ in $(seq 100); do scontrol ping 2>/dev/null | grep -q UP && break; alive "$slurmctld_pid" || break; sleep 0.2; done
scontrol ping | grep -q UP || fail "slurmctld does not answer"
slurmd -D -f "$SLURM_CONF" -N "$node" > "$tmp/log/slurmd.out.log" 2>&1 &
slurmd_pid=$!
state=""
for _ in $(seq 150); do
  state=$(sinfo -h -n "$node" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  alive "$slurmd_pid" || fail "slurmd exited"
  sleep 0.2
done
[ "$state" = idle ] || fail "node $node is '$state', not idle"

# --- the reference and the Slurm job --------------------------------------------
cd "$tmp/submit"
log "scene and reference render"
portico scene generate --preset demo building > /dev/null
portico render building -o reference.exr "${deploy_render_options[@]}" --workers 1 > /dev/null 2>&1

# Where the programs have CURVE keys and cells over the wire (--keys, --cache-dir),
# the job uses them as a multi-node one must (PORTICO_KEYS, PORTICO_CACHE_DIR).
secure=no
if "$bin/portico-worker" --help | grep -q -- --cache-dir && "$bin/portico-worker" --help | grep -q -- --keys \
   && "$bin/portico-coordinator" --help | grep -q -- --keys && portico keys --help > /dev/null 2>&1; then
  secure=yes
  portico keys generate "$tmp/keys" > /dev/null
  export PORTICO_KEYS="$tmp/keys" PORTICO_CACHE_DIR="$tmp/cache"
fi

log "sbatch deploy/slurm/portico.sbatch (1 node, 2 workers; CURVE keys and worker caches: $secure)"
# The command of docs/deploy.md, sized for this machine: one node, two tasks =
# two workers of one thread each. sbatch passes PATH (the build's bin/) on.
timeout 150 sbatch --wait --job-name=portico-test --nodes=1 --ntasks-per-node=2 --cpus-per-task=1 \
  --mem=2G --time=00:05:00 --output=portico-%j.out \
  "$source_dir/deploy/slurm/portico.sbatch" building image.exr "${deploy_render_options[@]}" \
  || fail "the Slurm job failed (sbatch --wait exit $?)"
out=$(ls portico-*.out)
cat "$out"
grep -q "2 worker(s)" "$out" || fail "the job did not start two workers"
[ "$(ls portico-*/worker-*.log | wc -l)" = 2 ] || fail "expected two worker logs"
[ "$(grep -Ec '\] worker .* joined' portico-*/coordinator.log)" = 2 ] || fail "expected two workers to join"
# The script stopped the services with SIGTERM (scancel --signal=TERM), not SIGKILL.
[ "$(grep -Ec '\] worker .* left$' portico-*/coordinator.log)" = 2 ] || fail "the workers did not leave cleanly"
grep -q "coordinator stopping" portico-*/coordinator.log || fail "the coordinator did not stop cleanly"
if [ $secure = yes ]; then
  grep -q "CURVE on" portico-*/coordinator.log || fail "the coordinator did not use the CURVE keys"
  [ -z "$(ls -A "$tmp/cache" 2>/dev/null)" ] || fail "the job left its worker caches in $tmp/cache"
fi
expect_same_pixels image.exr reference.exr
log "PASS"
