#!/usr/bin/env bash
# Installs every Debian 12 package gdvr builds, tests and runs with.
# Idempotent: packages already present are left alone; run as root (or with sudo available).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git python3 python3-pip python3-venv clang libclang-rt-14-dev
  # ray tracing, maths, parallelism
  libembree-dev libeigen3-dev libtbb-dev
  # images, colour, video
  libopenexr-dev libopencolorio-dev opencolorio-tools libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  libpng-dev libjpeg-dev libstb-dev
  # scene formats
  libpugixml-dev zlib1g-dev libtinygltf-dev nlohmann-json3-dev
  # service
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc libsqlite3-dev libssl-dev openssl
  python3-grpcio python3-protobuf python3-numpy python3-setuptools
  # tests
  libgtest-dev libgmock-dev
  # systemd-analyze verify of deploy/systemd (tests/farm)
  systemd
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
