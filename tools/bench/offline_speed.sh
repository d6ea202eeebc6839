#!/usr/bin/env bash
# Offline mapping speed and memory (issue 17), figures only, no thresholds:
#  - lanemap-offline on the demo drive (West Oakland, 60 s, seed 1, camera 10 Hz + VLP-16), truth
#    labels: on the LIDAR mesh (meshes on a second core, the default), on the LIDAR mesh with the
#    meshes in the main thread (--mesh-in-main-thread: one core), and on the flat plane
#    (--no-lidar); wall and CPU seconds, each as "x real time" beside the baseline, the drive's
#    own duration (issue 17's target: >= 20x on the mesh, keep the flat figure).
#  - peak RSS of lanemap-offline (LIDAR mesh, truth labels) on a 240 s and a 60 s Monaco drive
#    (seed 4), the 60 s figure the baseline (target: ratio <= 1.2).
# The drives are simulated first (about 3-6 minutes on 2 cores); OUT keeps them for a rerun.
#
#   tools/bench/offline_speed.sh BUILD_DIR [OUT]
set -euo pipefail

build=${1:-build}
bin=$build/bin
for b in lanemap-sim lanemap-offline; do
  [ -x "$bin/$b" ] || { echo "offline_speed.sh: no $bin/$b (build it first)" >&2; exit 2; }
done
[ -x /usr/bin/time ] || { echo "offline_speed.sh: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
if [ $# -ge 2 ]; then
  out=$2
  mkdir -p "$out"
else
  out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-offline-speed.XXXXXX")
  trap 'rm -rf "$out"' EXIT
fi

# sim NAME OSM DURATION SEED: a drive with camera and LIDAR, unless OUT holds it already.
sim() {
  [ -f "$out/$1/scenario.json" ] && return 0
  "$bin/lanemap-sim" -q --force --osm "$2" --out "$out/$1" --duration "$3" --seed "$4" 2> "$out/$1.sim.log" ||
    { cat "$out/$1.sim.log" >&2; exit 1; }
}
# offline NAME DRIVE [ARGS...]: maps DRIVE, leaves "wall user sys rss_kib" in $out/NAME.time.
offline() {
  local name=$1 drive=$2
  shift 2
  rm -rf "$out/$name"
  /usr/bin/time -o "$out/$name.time" -f "%e %U %S %M" "$bin/lanemap-offline" -q --oracle --log "$out/$drive/drive.lcmlog" \
    --osm "$out/$drive/roads.osm" --out "$out/$name" "$@" > "$out/$name.log" 2>&1 || { cat "$out/$name.log" >&2; exit 1; }
}

sim demo data/osm/west-oakland.osm 60 1
offline mesh demo
offline mesh-main demo --mesh-in-main-thread
offline flat demo --no-lidar
sim monaco60 data/osm/monaco.osm.pbf 60 4
sim monaco240 data/osm/monaco.osm.pbf 240 4
offline rss60 monaco60
offline rss240 monaco240

python3 - "$out" << 'EOF'
import json, sys
out = sys.argv[1]
def t(name):
    w, u, s, rss = open(f"{out}/{name}.time").read().split()
    return float(w), float(u) + float(s), int(rss)
def dur(drive):
    return json.load(open(f"{out}/{drive}/scenario.json"))["duration_s"]
def summary(name):
    return json.load(open(f"{out}/{name}/summary.json"))
d = dur("demo")
print(f"   demo drive (West Oakland, seed 1, camera 10 Hz + LIDAR, truth labels): {d:.1f} s")
print(f"   baseline (real time): {d:.1f} s")
for name, what in [("mesh", "LIDAR mesh, meshes on a second core (default)"),
                   ("mesh-main", "LIDAR mesh, meshes in the main thread      "),
                   ("flat", "flat plane (--no-lidar)                     ")]:
    w, c, rss = t(name)
    s = summary(name)
    print(f"   {what}: wall {w:6.2f} s = {d / w:5.1f}x real time, CPU {c:6.2f} s = {d / c:5.1f}x"
          f"  ({s['frames_mesh']} of {s['frames_projected']} frames on the mesh, {s['roads_mapped']} roads)")
same = open(f"{out}/mesh/map.osm", "rb").read() == open(f"{out}/mesh-main/map.osm", "rb").read()
print(f"   the two mesh runs' maps are {'byte-identical' if same else 'DIFFERENT'}")
print("   target: >= 20x real time on the mesh (wall, 2 cores)")
w60, _, r60 = t("rss60")
w240, _, r240 = t("rss240")
print(f"   peak RSS, Monaco seed 4, LIDAR mesh: 60 s drive {r60 / 1024:.0f} MiB (baseline), "
      f"{dur('monaco240'):.0f} s drive {r240 / 1024:.0f} MiB: ratio {r240 / r60:.2f} (target <= 1.2); "
      f"{summary('rss60')['roads_mapped']} and {summary('rss240')['roads_mapped']} roads")
EOF
