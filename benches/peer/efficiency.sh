#!/usr/bin/env bash
# Equal-time quality (issue 11): efficiency = 1 / (MSE x seconds) of each renderer's image
# against a high-spp reference, on cornell-classic (Lightpath, Mitsuba 3 llvm_ad_rgb,
# Blender Cycles; reference ref/cornell_ref.exr, Mitsuba 65536 spp) and on
# scenes/many-lights.toml (a key, a dim dome and 48 small lamps; Lightpath only, the
# other renderers have no reader for it; reference rendered here by Lightpath).
# Renderers alternate within each repetition; the summary takes medians and ratios.
# The machine's load makes single timings noisy: read the ratios of medians.
#
# Needs (installed by hand, not by CI):  pip install mitsuba==3.9.1 numpy bpy==5.0.1
#                                        apt-get install -y libllvm19
# Usage: benches/peer/efficiency.sh [SPP] [REPEATS]      (defaults 64 and 3)
#   LIGHTPATH_BASELINE=/path/to/older/lightpath  also times an older build on both
#   scenes with its defaults (how "today's efficiency" was measured).
#   EFFICIENCY_SKIP_PEERS=1  Lightpath only.
#   LIGHTPATH=/path/to/lightpath  times that binary instead of building this tree's.
#   LIGHTPATH_ADAPTIVE="--min-spp 64 --spp 1024 --noise-threshold 0.1"  adds Lightpath
#   with these sampling flags (adaptive sampling) on both scenes.
#   CYCLES_ADAPTIVE="0.01 16 1024"  adds Cycles with its adaptive sampling on: threshold,
#   min samples, max samples.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"
spp="${1:-64}"
repeats="${2:-3}"
if [ -n "${LIGHTPATH:-}" ]; then
  lightpath="$LIGHTPATH"
else
  cargo build --profile dist --manifest-path "$root/Cargo.toml" >/dev/null
  lightpath="${CARGO_TARGET_DIR:-$root/target}/release/lightpath"
fi
many="$root/scenes/many-lights.toml"
many_ref="$out/many_lights_ref.exr"

seconds() { sed -n 's/^.*AOVs: \([0-9.]*\) s,.*/\1/p'; }

if [ ! -f "$many_ref" ]; then
  echo "rendering the many-lights reference (4096 spp, seed 99) ..." >&2
  "$lightpath" render "$many" --quiet --aovs none --spp 4096 --seed 99 --threads 2 \
    --clamp-indirect 0 -o "$many_ref" >/dev/null
fi

results="$out/efficiency.txt"
: > "$results"
for i in $(seq 1 "$repeats"); do
  if [ -z "${EFFICIENCY_SKIP_PEERS:-}" ]; then
    python3 "$here/mitsuba_cornell.py" --variant llvm_ad_rgb --spp "$spp" --max-depth 8 --threads 2 \
        --seed "$i" --repeat 2 --out "$out/eff_mitsuba_$i" \
      | sed -n "s/^RESULT.* best_s=\([0-9.]*\).*/RESULT scene=cornell-classic renderer=mitsuba_llvm_ad_rgb seconds=\1 image=eff_mitsuba_$i.exr/p" >> "$results"
    python3 "$here/cycles_cornell.py" --spp "$spp" --max-depth 8 --threads 2 --seed "$i" --repeat 2 \
        --beauty-only --out "$out/eff_cycles_$i" 2>/dev/null \
      | sed -n "s/^RESULT.* best_s=\([0-9.]*\).*/RESULT scene=cornell-classic renderer=cycles seconds=\1 image=eff_cycles_$i.exr/p" >> "$results"
    if [ -n "${CYCLES_ADAPTIVE:-}" ]; then
      read -r c_threshold c_min c_max <<< "$CYCLES_ADAPTIVE"
      python3 "$here/cycles_cornell.py" --spp "$c_max" --adaptive-threshold "$c_threshold" \
          --adaptive-min-samples "$c_min" --max-depth 8 --threads 2 --seed "$i" --repeat 2 \
          --beauty-only --out "$out/eff_cycles_adaptive_$i" 2>/dev/null \
        | sed -n "s/^RESULT.* best_s=\([0-9.]*\).*/RESULT scene=cornell-classic renderer=cycles_adaptive seconds=\1 image=eff_cycles_adaptive_$i.exr/p" >> "$results"
    fi
  fi
  t=$("$lightpath" render cornell-classic --quiet --aovs none --spp "$spp" --threads 2 --seed "$i" \
      -o "$out/eff_lightpath_$i.exr" | seconds)
  echo "RESULT scene=cornell-classic renderer=lightpath seconds=$t image=eff_lightpath_$i.exr" >> "$results"
  t=$("$lightpath" render "$many" --quiet --aovs none --spp "$spp" --threads 2 --seed "$i" \
      --clamp-indirect 0 -o "$out/eff_many_$i.exr" | seconds)
  echo "RESULT scene=many-lights renderer=lightpath seconds=$t image=eff_many_$i.exr" >> "$results"
  if [ -n "${LIGHTPATH_ADAPTIVE:-}" ]; then
    read -r -a adaptive <<< "$LIGHTPATH_ADAPTIVE"
    t=$("$lightpath" render cornell-classic --quiet --aovs none "${adaptive[@]}" --threads 2 \
        --seed "$i" -o "$out/eff_lightpath_adaptive_$i.exr" | seconds)
    echo "RESULT scene=cornell-classic renderer=lightpath_adaptive seconds=$t image=eff_lightpath_adaptive_$i.exr" >> "$results"
    t=$("$lightpath" render "$many" --quiet --aovs none "${adaptive[@]}" --threads 2 --seed "$i" \
        --clamp-indirect 0 -o "$out/eff_many_adaptive_$i.exr" | seconds)
    echo "RESULT scene=many-lights renderer=lightpath_adaptive seconds=$t image=eff_many_adaptive_$i.exr" >> "$results"
  fi
  if [ -n "${LIGHTPATH_BASELINE:-}" ]; then
    t=$("$LIGHTPATH_BASELINE" render cornell-classic --quiet --aovs none --spp "$spp" --threads 2 \
        --seed "$i" -o "$out/eff_baseline_$i.exr" | seconds)
    echo "RESULT scene=cornell-classic renderer=lightpath_baseline seconds=$t image=eff_baseline_$i.exr" >> "$results"
    t=$("$LIGHTPATH_BASELINE" render "$many" --quiet --aovs none --spp "$spp" --threads 2 \
        --seed "$i" -o "$out/eff_many_baseline_$i.exr" | seconds)
    echo "RESULT scene=many-lights renderer=lightpath_baseline seconds=$t image=eff_many_baseline_$i.exr" >> "$results"
  fi
done
cat "$results"
python3 "$here/efficiency.py" "$results" "$out" cornell-classic="$here/ref/cornell_ref.exr" \
  many-lights="$many_ref"
