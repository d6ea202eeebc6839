#!/usr/bin/env bash
# Bundles the viewer's page at build time (CMake calls it; no CDN, nothing fetched at run time):
#   web/viewer/build.sh SRC_DIR OUT_DIR WORK_DIR
# npm ci installs exactly what package-lock.json pins (Leaflet) into WORK_DIR (only when the lock
# changed), then the page (SRC_DIR/src) and Leaflet's dist files are copied to OUT_DIR, which
# lanemap-viewer serves (build/share/lanemap/viewer). Needs npm (scripts/install-deps.sh) and the
# npm registry once; the npm cache (~/.npm) serves later builds.
set -euo pipefail
src=$1 out=$2 work=$3
command -v npm > /dev/null || { echo "web/viewer/build.sh: npm not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
mkdir -p "$work"
cp "$src/package.json" "$src/package-lock.json" "$work/"
if [ ! -f "$work/node_modules/leaflet/dist/leaflet.js" ] || ! cmp -s "$src/package-lock.json" "$work/node_modules/.lanemap-lock"; then
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
  cp "$src/package-lock.json" "$work/node_modules/.lanemap-lock"
fi
rm -rf "$out.tmp"
mkdir -p "$out.tmp/leaflet/images"
cp "$work/node_modules/leaflet/dist/leaflet.js" "$work/node_modules/leaflet/dist/leaflet.css" "$out.tmp/leaflet/"
cp "$work/node_modules/leaflet/dist/images/"*.png "$out.tmp/leaflet/images/"
cp "$work/node_modules/leaflet/LICENSE" "$out.tmp/leaflet/LICENSE.txt"
cp -R "$src/src/." "$out.tmp/"
rm -rf "$out"
mv "$out.tmp" "$out"
