#!/usr/bin/env bash
# Installs everything portico needs to build, run and test on Debian bookworm.
# Idempotent: re-running only refreshes the package lists and installs what is missing.
#
#   deploy/install-deps.sh            build, run and test dependencies
#   deploy/install-deps.sh --slurm    also Slurm (slurmctld, slurmd, srun, sbatch) and MUNGE,
#                                     for deploy/slurm/ and its test (tests/deploy/slurm_test.sh)
#   deploy/install-deps.sh --fuzz     also clang and libFuzzer, for tests/fuzz (docs/fuzzing.md)
#   deploy/install-deps.sh --peers    also Mitsuba 3 and Dr.Jit (PyPI) in a virtual environment at
#                                     $MITSUBA_VENV (default ~/.local/share/portico/mitsuba-venv) with
#                                     Debian's libllvm19, for `portico bench quality --mitsuba`
#                                     (docs/image-quality.md; --mitsuba: the same)
set -euo pipefail

mitsuba=0
packages=(
  cmake ninja-build g++ pkg-config make
  libembree-dev libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev
  libzmq3-dev cppzmq-dev
  capnproto libcapnp-dev
  libsqlite3-dev sqlite3
  libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libtbb-dev libassimp-dev zlib1g-dev
  liberfa-dev
  libcpp-httplib-dev
  python3 python3-yaml python3-venv
  # The namespace test (tests/deploy/netns_test.sh): ip netns, veth pairs, tc; unshare.
  iproute2 util-linux
  # `portico dashboard`'s test drives the page in a headless browser (tests/dashboard/).
  chromium chromium-driver python3-selenium
)

for arg in "$@"; do
  case "$arg" in
    --slurm) packages+=(slurm-wlm munge) ;;
    # bookworm's clang is 14; its libFuzzer (libclang_rt.fuzzer) is in
    # libclang-rt-14-dev, only recommended by clang, so named here.
    --fuzz) packages+=(clang libclang-rt-14-dev) ;;
    # Dr.Jit's LLVM back end (llvm_ad_rgb) loads libLLVM at run time.
    --peers|--mitsuba) packages+=(libllvm19); mitsuba=1 ;;
    -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "install-deps.sh: unknown option $arg (known: --slurm, --fuzz, --peers)" >&2; exit 2 ;;
  esac
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

export DEBIAN_FRONTEND=noninteractive
# Wait for another apt/dpkg run (another install on the same machine) instead of failing.
apt_opts=(-o DPkg::Lock::Timeout=600)
$SUDO apt-get "${apt_opts[@]}" update -qq
$SUDO apt-get "${apt_opts[@]}" install -y -qq --no-install-recommends "${packages[@]}"

# IFC import (`portico scene import model.ifc`, docs/importing-buildings.md)
# reads models with IfcOpenShell, which Debian does not package: a virtual
# environment beside the sources holds it (and numpy), as the user running
# this script, where `portico` looks for it.
repo="$(cd "$(dirname "$0")/.." && pwd)"
if [ ! -x "$repo/.venv/bin/python3" ]; then python3 -m venv "$repo/.venv"; fi
# Radiance (PyPI's pyradiance ships its programs: oconv, rtrace, gensky, ...
# in pyradiance/bin, their library in pyradiance/lib for RAYPATH) checks
# portico's illuminance: `scene export FILE.rad`, the comparison tests and
# `bench analyze` (docs/radiance.md).
# NVIDIA's FLIP (flip-evaluator) scores images per pixel beside the block
# metric: portico-compare, `bench quality` and the reference tests
# (docs/image-quality.md).
"$repo/.venv/bin/python3" -m pip install -q --disable-pip-version-check "ifcopenshell==0.9.0.post1" "numpy>=1.24" \
  "pyradiance==1.3.1" "flip-evaluator==1.7"
# LuxCoreRender (PyPI's pyluxcore, with its PhotonGI cache: the nearest
# open-source photon-mapping peer) renders beside portico in `bench quality
# --luxcore` (python/portico_peers; docs/image-quality.md).
"$repo/.venv/bin/python3" -m pip install -q --disable-pip-version-check "pyluxcore==2.11.2"

if [ "$mitsuba" = 1 ]; then
  venv="${MITSUBA_VENV:-$HOME/.local/share/portico/mitsuba-venv}"
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
  "$venv/bin/pip" install -q mitsuba==3.9.1 drjit==1.5.0 numpy
  echo "Mitsuba 3 in $venv: portico bench quality DIR --mitsuba renders with it (docs/image-quality.md)"
fi
