#!/usr/bin/env bash
# make demo: simulate a drive over the bundled West Oakland street network and write the
# ground-truth lane map with a picture. Usage: scripts/demo.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:-build}
out=${2:-demo-out}
osm=data/osm/west-oakland.osm
bin=$build/bin
rm -rf "$out"
mkdir -p "$out"

echo "== skeleton of $osm"
"$bin/lanemap-skeleton" --osm "$osm" --geojson "$out/skeleton.geojson" --png "$out/skeleton.png"

echo "== simulating a 60 s drive (seed 1)"
"$bin/lanemap-sim" --osm "$osm" --out "$out/drive" --duration 60 --seed 1

echo "== what the log holds"
"$bin/lanemap-lcm-stats" --log "$out/drive/drive.lcmlog"

cat <<EOT

Demo output in $out/:
  skeleton.png / skeleton.geojson   the OSM skeleton: atomic roads and intersection ROIs
  drive/drive.lcmlog                the simulated drive (replay: lcm-logplayer $out/drive/drive.lcmlog)
  drive/groundtruth.osm             the true lane-level map (Lanelet2)
  drive/groundtruth.png             a picture of it over the street network
  drive/roads.osm                   the road-level OSM the mapper is given
  drive/scenario.json               route, seed, options, counts
Map data (c) OpenStreetMap contributors, ODbL.
EOT
