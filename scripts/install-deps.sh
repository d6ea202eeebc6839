#!/usr/bin/env bash
# Installs the Debian packages lanemap needs, only when something is missing (idempotent).
# Usage: scripts/install-deps.sh [PACKAGE ...]   (as root, or with sudo available)
# Without arguments: lanemap's build and test packages; with arguments: those packages instead
# (scripts/install-train-deps.sh uses this for the training tools). The last line's packages are for
# Lanelet2's own checks (../shared/tools/lanelet2/build.sh, run by tests/lanelet2_tools).
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config git
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev default-jdk-headless
  libeigen3-dev libopencv-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libgeographiclib-dev libpcl-dev libv4l-dev libosmium2-dev libprotozero-dev libbz2-dev zlib1g-dev libexpat1-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev
  osmium-tool iproute2 util-linux
  chromium chromium-driver                # the viewer's browser test (tests/viewer/browser_test.cc)
  clang libclang-rt-14-dev                # fuzz/: libFuzzer with ASan + UBSan (make fuzz)
  slurm-wlm munge                         # lanemap-city --slurm's test: a one-node cluster (tests/mapping/city_test.cc)
  libboost-filesystem-dev libboost-serialization-dev libboost-program-options-dev libpugixml-dev  # Lanelet2's checks
)
# npm bundles the viewer's page at build time (web/viewer); a Node.js from elsewhere (NodeSource's
# nodejs ships its own npm and conflicts with Debian's) is kept.
if ! command -v npm > /dev/null; then PACKAGES+=(nodejs npm); fi
if [ $# -gt 0 ]; then PACKAGES=("$@"); fi
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
