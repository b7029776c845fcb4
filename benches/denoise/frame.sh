#!/usr/bin/env bash
# Denoising speed on a production-sized frame (issue 29, part 3): the built-in cornell
# at 1920×1080 and 4 spp with 41 AOVs (the standard set, three light groups splitting
# beauty and six more AOVs, four bounce AOVs, two variances), then `lightpath denoise`
# timed (wall clock, CPU time, peak memory). Target: ≤ 60 s wall on 2 idle cores.
#
#     benches/denoise/frame.sh LIGHTPATH [BASELINE] [--dir DIR]
#
# LIGHTPATH (and BASELINE, an older build to compare with, run right after it on the
# same file) are binaries built with `--features denoise`; OIDN_DIR / LD_LIBRARY_PATH as
# .ci/run sets them. The frame is rendered once, with LIGHTPATH, and kept in DIR.
set -euo pipefail
lightpath=${1:?usage: frame.sh LIGHTPATH [BASELINE] [--dir DIR]}
shift
baseline=
if [ $# -gt 0 ] && [ "$1" != --dir ]; then
  baseline=$1
  shift
fi
dir=/tmp/lightpath-denoise-frame
if [ "${1:-}" = --dir ]; then
  dir=${2:?--dir needs a directory}
fi
mkdir -p "$dir"
frame="$dir/frame.exr"
if [ ! -f "$frame" ]; then
  "$lightpath" render cornell --resolution 1920x1080 --spp 4 --light-groups \
    --light-group-aovs directDiffuse,indirectDiffuse,directSpecular,indirectSpecular,diffuse,specular \
    --bounces 3 --variance directDiffuse_key,indirectSpecular -o "$frame"
fi
"$lightpath" aovs "$frame" | head -n 1
time_denoise() {
  local bin=$1 out=$2
  echo "== $bin (load: $(cut -d' ' -f1-3 /proc/loadavg))"
  /usr/bin/time -f "%U s user, %S s system, %e s wall, %M KB peak" \
    "$bin" denoise "$frame" -o "$out" 2>&1 | grep -v '^denoising '
  "$bin" aovs "$out" | grep -c '^FAIL' | sed 's/^/partition or channel checks failing: /' || true
}
time_denoise "$lightpath" "$dir/denoised.exr"
if [ -n "$baseline" ]; then
  time_denoise "$baseline" "$dir/denoised-baseline.exr"
fi
