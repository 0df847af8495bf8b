#!/usr/bin/env bash
# Installs every Debian package vdb_shell needs to build, test and benchmark.
# Idempotent: packages already present are left alone; apt-get update runs only when
# something is missing. Run as root (or through sudo) on Debian 12.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config clang-format clang libclang-rt-14-dev
  libopenvdb-dev libboost-dev libtbb-dev libpng-dev
  libgtest-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev
  libopenvdb-tools gmsh tetgen chromium
  python3-meshio python3-numpy python3-scipy python3-matplotlib python3-openvdb
  python3-dev pybind11-dev python3-pytest
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
