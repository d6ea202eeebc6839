#!/usr/bin/env bash
# Installs the Debian packages the segmentation training tools (tools/seg/) need, only when one is
# missing (idempotent). Not part of `make test` or `make demo`: the shipped model (models/) is
# used by the C++ segmenter through OpenCV DNN, which needs no Python.
# Usage: scripts/install-train-deps.sh      (as root, or with sudo available)
# The training scripts run with /usr/bin/python3 (Debian's interpreter, where these packages land).
set -euo pipefail
exec "$(dirname "$0")/install-deps.sh" python3-torch python3-onnx python3-opencv python3-numpy
