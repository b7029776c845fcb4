#!/usr/bin/env bash
# Lightpath against Mitsuba 3 on cornell-classic (256x256, max depth 8, Russian roulette
# from depth 5, box filter, 2 threads): samples/s of each, their ratio, and the RMSE of
# each image against the 65536-spp reference in ref/.
#
# Needs (installed by hand, not by CI):  pip install mitsuba==3.9.1 numpy
#                                        apt-get install -y libllvm19   (for llvm_ad_rgb)
# Usage: benches/peer/run.sh [SPP] [REPEATS]        (defaults 64 and 3)
#        benches/peer/run.sh --reference            (re-render ref/ with Mitsuba, ~25 min)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"

if [ "${1:-}" = "--reference" ]; then
  python3 "$here/mitsuba_cornell.py" --variant llvm_ad_rgb --spp 65536 --pass-spp 256 --max-depth 8 \
    --threads 2 --seed 1000000 --out "$here/ref/cornell_ref"
  exit 0
fi

spp="${1:-64}"
repeats="${2:-3}"
cargo build --profile dist --manifest-path "$root/Cargo.toml" >/dev/null
lightpath="${CARGO_TARGET_DIR:-$root/target}/release/lightpath"

for i in $(seq 1 "$repeats"); do
  for variant in llvm_ad_rgb scalar_rgb; do
    python3 "$here/mitsuba_cornell.py" --variant "$variant" --spp "$spp" --max-depth 8 --threads 2 \
      --out "$out/mitsuba_$variant" | grep '^RESULT' | sed "s/^/run=$i /"
  done
  "$lightpath" render cornell-classic --quiet --aovs none --spp "$spp" --threads 2 -o "$out/lightpath.exr" \
    | sed -n "s/^.*s, \([0-9.]*\) M samples\/s.*/RESULT run=$i variant=lightpath Msamples_per_s=\1/p"
  "$lightpath" render cornell-classic --quiet --spp "$spp" --threads 2 --light-groups \
      --bounces 3 --light-group-aovs emission,diffuse,specular,directDiffuse,indirectDiffuse,directSpecular,indirectSpecular,subsurface,transmissive,albedo \
      -o "$out/lightpath_aovs.exr" \
    | sed -n "s/^.*s, \([0-9.]*\) M samples\/s.*/RESULT run=$i variant=lightpath_40aovs Msamples_per_s=\1/p"
  # The issue's literal case, a 3-group split: the built-in 'cornell' has key and fill
  # lights and a glowing ball (the default part), so the standard set splits in three.
  "$lightpath" render cornell --quiet --aovs none --spp "$spp" --resolution 256x256 --threads 2 \
      -o "$out/lightpath_cornell.exr" \
    | sed -n "s/^.*s, \([0-9.]*\) M samples\/s.*/RESULT run=$i variant=lightpath_cornell Msamples_per_s=\1/p"
  "$lightpath" render cornell --quiet --spp "$spp" --resolution 256x256 --threads 2 --light-groups \
      --light-group-aovs emission,diffuse,specular,directDiffuse,indirectDiffuse,directSpecular,indirectSpecular,subsurface,transmissive,albedo \
      -o "$out/lightpath_cornell_aovs.exr" \
    | sed -n "s/^.*s, \([0-9.]*\) M samples\/s.*/RESULT run=$i variant=lightpath_cornell_44aovs Msamples_per_s=\1/p"
done | tee "$out/results.txt"

python3 "$here/compare.py" "$out/results.txt" "$here/ref/cornell_ref.exr" \
  "$out/mitsuba_llvm_ad_rgb.exr" "$out/mitsuba_scalar_rgb.exr" "$out/lightpath.exr"

# The AOVs of the timed renders add up (standard set, light-group parts, bounces).
"$lightpath" aovs "$out/lightpath_aovs.exr" | grep -E '^(ok|FAIL)'
"$lightpath" aovs "$out/lightpath_cornell_aovs.exr" | grep -E '^(ok|FAIL)'

"$here/scaling.sh" "$repeats"
