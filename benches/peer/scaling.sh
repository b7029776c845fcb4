#!/usr/bin/env bash
# Lightpath alone (no Mitsuba needed): how cornell-classic scales with threads and with
# resolution, and the peak memory of a 1920x1080 render with the harness's ~40 AOVs
# against the film it must hold. run.sh calls it after the comparison.
#
# Usage: benches/peer/scaling.sh [REPEATS]     (default 3; medians)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"
repeats="${1:-3}"
cargo build --profile dist --manifest-path "$root/Cargo.toml" >/dev/null
lightpath="${CARGO_TARGET_DIR:-$root/target}/release/lightpath"
aovs=(--light-groups --bounces 3 --light-group-aovs
  emission,diffuse,specular,directDiffuse,indirectDiffuse,directSpecular,indirectSpecular,subsurface,transmissive,albedo)

# Prints the render's seconds (the renderer's own clock, without loading and writing).
seconds() {
  "$lightpath" render cornell-classic --quiet -o "$out/scaling.exr" "$@" \
    | sed -n 's/^.*AOVs: \([0-9.]*\) s,.*/\1/p'
}

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

run() { for _ in $(seq 1 "$repeats"); do seconds "$@"; done | median; }

t1=$(run --aovs none --spp 32 --threads 1)
t2=$(run --aovs none --spp 32 --threads 2)
echo "threads: 1 thread ${t1} s, 2 threads ${t2} s (256x256, 32 spp): speed-up $(echo "$t1 / $t2" | bc -l | cut -c1-4)x"

small=$(run --aovs none --spp 16 --threads 2 --resolution 256x256)
large=$(run --aovs none --spp 16 --threads 2 --resolution 1024x1024)
echo "resolution: 256x256 ${small} s, 1024x1024 ${large} s (16x the pixels): $(echo "$large / $small" | bc -l | cut -c1-5)x the time"

if [ -x /usr/bin/time ]; then
  /usr/bin/time -v "$lightpath" render cornell-classic --quiet --spp 1 --resolution 1920x1080 \
    "${aovs[@]}" -o "$out/memory.exr" > "$out/memory.txt" 2> "$out/memory.time"
  rss_kb=$(sed -n 's/^.*Maximum resident set size (kbytes): //p' "$out/memory.time")
  n=$(sed -n 's/^.*at 1 spp, \([0-9]*\) AOVs.*/\1/p' "$out/memory.txt")
  film=$((1920 * 1080 * (3 * n + 1) * 4))
  budget=$((1920 * 1080 * 40 * 3 * 4))
  echo "memory: 1920x1080 with $n AOVs: peak RSS $((rss_kb / 1024)) MiB;" \
    "film $((film / 1048576)) MiB; peak / film $(echo "$rss_kb * 1024 / $film" | bc -l | cut -c1-4);" \
    "peak / (40 AOVs x 12 B/pixel) $(echo "$rss_kb * 1024 / $budget" | bc -l | cut -c1-4) (target <= 1.10)"
else
  echo "memory: skipped (/usr/bin/time not installed)"
fi
