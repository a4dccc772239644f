#!/usr/bin/env bash
# deploy/systemd: `systemd-analyze verify` on portico-coordinator.service and
# portico-worker@.service (the template and an instance), failing on any warning
# it prints about them (it exits 0 on unknown keys and bad values); and every
# --flag in their ExecStart= is one the program knows (--help).
# Skips (exit 77) where systemd-analyze is not installed: installing systemd is
# not something a test should do to a machine.
#   systemd_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
source "$source_dir/tests/deploy/lib.sh"
units="$source_dir/deploy/systemd"

# A coordinator holds a descriptor per connection: the default limit of 1024 is too few.
for unit in portico-coordinator.service portico-worker@.service; do
  grep -q '^LimitNOFILE=[0-9]' "$units/$unit" || fail "$unit: no LimitNOFILE= (the default 1024 descriptors are too few)"
done

if ! command -v systemd-analyze > /dev/null; then
  echo "SKIP: systemd-analyze is not installed (Debian package systemd); the units are not verified"
  exit $DEPLOY_SKIP
fi

tmp=$(mktemp -d /tmp/portico-systemd-test.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
# verify checks that ExecStart's program exists: point it at this build's.
for unit in portico-coordinator.service portico-worker@.service; do
  sed "s|/usr/local/bin/|$bin/|g" "$units/$unit" > "$tmp/$unit"
done
ln -s portico-worker@.service "$tmp/portico-worker@1.service"

status=0
systemd-analyze verify --man=no "$tmp/portico-coordinator.service" "$tmp/portico-worker@.service" \
  "$tmp/portico-worker@1.service" > "$tmp/verify.out" 2>&1 || status=$?
cat "$tmp/verify.out"
[ $status -eq 0 ] || fail "systemd-analyze verify exited $status"
if grep -q "portico" "$tmp/verify.out"; then fail "systemd-analyze verify warns about the units"; fi
log "systemd-analyze verify: no warning ($(systemd-analyze --version | head -n 1))"

# Every option of ExecStart= exists in the program. --keys and --cache-dir are
# being added to the programs (issue 6): until they are, a note, not a failure.
pending="--keys --cache-dir"
for unit in portico-coordinator.service portico-worker@.service; do
  line=$(sed -n 's/^ExecStart=//p' "$units/$unit")
  program=$(basename "$(echo "$line" | awk '{ print $1 }')")
  help=$("$bin/$program" --help)
  for flag in $(echo "$line" | grep -o -- '--[a-z][a-z-]*' | sort -u); do
    if ! grep -q -- "$flag" <<< "$help"; then
      case " $pending " in
        *" $flag "*) log "note: $program has no $flag yet ($unit uses it)" ;;
        *) fail "$unit: $program has no option $flag" ;;
      esac
    fi
  done
  grep -q '^EnvironmentFile=/etc/portico/portico.env$' "$units/$unit" || fail "$unit: no EnvironmentFile"
  for variable in $(echo "$line" | grep -oE '\$\{?[A-Z_]+' | tr -d '${'); do
    grep -q "^$variable=" "$units/portico.env" || fail "$unit uses \${$variable}, not set in portico.env"
  done
done
# The workers' pools: portico-worker reads PORTICO_WORKER_TAGS from the environment the
# EnvironmentFile gives it, and says so in its --help.
grep -q '^PORTICO_WORKER_TAGS=' "$units/portico.env" || fail "portico.env sets no PORTICO_WORKER_TAGS (the workers' pools)"
"$bin/portico-worker" --help | grep -q 'PORTICO_WORKER_TAGS' || fail "portico-worker --help does not name PORTICO_WORKER_TAGS"
log "PASS"
