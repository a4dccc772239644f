#!/usr/bin/env bash
# Installs everything portico needs to build, run and test on Debian bookworm.
# Idempotent: re-running only refreshes the package lists and installs what is missing.
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config make
  libembree-dev libopenimageio-dev openimageio-tools
  libzmq3-dev cppzmq-dev
  capnproto libcapnp-dev
  libsqlite3-dev sqlite3
  libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libtbb-dev libassimp-dev zlib1g-dev
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${packages[@]}"
