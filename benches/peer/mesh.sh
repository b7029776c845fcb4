#!/usr/bin/env bash
# Lightpath against Mitsuba 3 llvm_ad_rgb on cornell-classic and on the same box with an
# 81,920-triangle bumpy sphere in it (bumpy_sphere.py, the mesh of `cargo bench`):
# Lightpath's whole process (load, BVH build, render, EXR write) against Mitsuba's render
# alone, alternating in one run; medians and ratios at the end.
#
# Needs (installed by hand, not by CI):  pip install mitsuba==3.9.1 numpy
#                                        apt-get install -y libllvm19 bc
# Usage: benches/peer/mesh.sh [SPP] [REPEATS] [LIGHTPATH_BINARY]   (defaults 64, 5, the
#        release build in $CARGO_TARGET_DIR or target/)
#        LIGHTPATH_ARGS="--accel embree" adds options to Lightpath's command line (a build
#        with the `embree` feature traces with Intel Embree).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"
spp="${1:-64}"
repeats="${2:-5}"
lightpath="${3:-${CARGO_TARGET_DIR:-$root/target}/release/lightpath}"

python3 "$here/bumpy_sphere.py" 6 "$out/bumpy.obj" >/dev/null
{
  cat "$root/scenes/cornell-classic.toml"
  cat <<'TOML'

[materials.mesh]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]

[[objects]]
shape = "obj"
name = "mesh"
material = "mesh"
file = "bumpy.obj"
TOML
} >"$out/cornell_mesh.toml"

samples=$((256 * 256 * spp))
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for i in $(seq 1 "$repeats"); do
  for scene in box mesh; do
    extra=()
    lp_scene=cornell-classic
    if [ "$scene" = mesh ]; then
      extra=(--extra-obj "$out/bumpy.obj" --obj-to-world 1 0 0 0)
      lp_scene="$out/cornell_mesh.toml"
    fi
    python3 "$here/mitsuba_cornell.py" --variant llvm_ad_rgb --spp "$spp" --max-depth 8 --threads 2 \
      --no-write "${extra[@]}" |
      sed -n "s/^RESULT.*Msamples_per_s_best=\([0-9.]*\).*/RESULT run=$i scene=$scene renderer=mitsuba_llvm Msamples_per_s=\1/p"
    start=$(date +%s.%N)
    # shellcheck disable=SC2086 # LIGHTPATH_ARGS is words
    "$lightpath" render "$lp_scene" --quiet --aovs none --spp "$spp" --threads 2 ${LIGHTPATH_ARGS:-} \
      -o "$out/lightpath_$scene.exr" >/dev/null
    end=$(date +%s.%N)
    echo "RESULT run=$i scene=$scene renderer=lightpath_process Msamples_per_s=$(echo "$samples / ($end - $start) / 1000000" | bc -l | cut -c1-6)"
  done
done | tee "$out/mesh_results.txt"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

python3 - "$out/mesh_results.txt" <<'PY'
import re, statistics, sys
runs = {}
for line in open(sys.argv[1]):
    m = re.match(r"RESULT run=(\d+) scene=(\w+) renderer=(\w+) Msamples_per_s=([0-9.]+)", line)
    if m:
        runs.setdefault((m[2], m[3]), []).append(float(m[4]))
for scene in ("box", "mesh"):
    mi = runs.get((scene, "mitsuba_llvm"), [])
    lp = runs.get((scene, "lightpath_process"), [])
    if mi and lp:
        a, b = statistics.median(lp), statistics.median(mi)
        print(f"{scene}: Lightpath {a:.3f} ({min(lp):.3f}-{max(lp):.3f}) M samples/s, "
              f"Mitsuba llvm_ad_rgb {b:.3f} ({min(mi):.3f}-{max(mi):.3f}); ratio {a / b:.2f}x")
PY
