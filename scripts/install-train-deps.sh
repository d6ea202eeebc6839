#!/usr/bin/env bash
# Installs the Debian packages the segmentation training tools (tools/seg/) need, only when one is
# missing (idempotent). Not part of `make test` or `make demo`: the shipped model (models/) is
# used by the C++ segmenter through OpenCV DNN, which needs no Python.
# Usage: scripts/install-train-deps.sh      (as root, or with sudo available)
# The training scripts run with /usr/bin/python3 (Debian's interpreter, where these packages land).
set -euo pipefail
PACKAGES=(python3-torch python3-onnx python3-opencv python3-numpy)
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-train-deps: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "install-train-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-train-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
