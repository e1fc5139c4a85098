#!/usr/bin/env bash
# Installs the Debian packages btr-dem needs (only those missing), then configures and builds.
# Idempotent: when everything is installed and built it returns in seconds.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${BTR_BUILD_DIR:-$here/build}

packages=(
  cmake g++ make pkg-config
  libeigen3-dev libgtest-dev libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libvtk9-dev zlib1g-dev
  liggghts yade openmpi-bin
  python3-numpy python3-scipy python3-matplotlib python3-pytest
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  # --no-install-recommends: liggghts recommends paraview, whose Python package conflicts with python3-vtk9.
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$(nproc)"
