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

# Intel Open Image Denoise, optional (the report's pt-oidn baselines): not a
# Debian 12 package. Its official build ships in the PyPI wheel pyoidn
# (library and CMake package), installed into this venv, where CMake looks
# (GDVR_OIDN_VENV). Pinned: core/denoise/oidn_api.h was checked against 2.5.1.
OIDN_VENV="${GDVR_OIDN_VENV:-/opt/gdvr/oidn-venv}"
OIDN_WHEEL="pyoidn==2.5.1.0"

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Never fails the script: gdvr builds and runs without OIDN. GDVR_WITH_OIDN=0
# leaves it out (as the CMake option of that name does).
install_oidn() {
  if [ "${GDVR_WITH_OIDN:-1}" = "0" ]; then
    echo "install-deps: Open Image Denoise left out (GDVR_WITH_OIDN=0)"
    return 0
  fi
  if compgen -G "$OIDN_VENV/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2*" >/dev/null; then
    echo "install-deps: Open Image Denoise present in $OIDN_VENV"
    return 0
  fi
  echo "install-deps: installing Open Image Denoise ($OIDN_WHEEL) into $OIDN_VENV"
  if ! { [ -x "$OIDN_VENV/bin/pip" ] || $SUDO python3 -m venv "$OIDN_VENV"; }; then
    echo "install-deps: WARNING: cannot create the venv $OIDN_VENV; building without Open Image Denoise" >&2
    return 0
  fi
  if ! $SUDO "$OIDN_VENV/bin/pip" install --quiet --disable-pip-version-check --timeout 30 --retries 1 \
      "$OIDN_WHEEL"; then
    echo "install-deps: WARNING: could not install $OIDN_WHEEL from PyPI (offline?); building without" \
         "Open Image Denoise (no pt-oidn report baselines). Run this script again when PyPI is reachable." >&2
    return 0
  fi
}
install_oidn
