#!/usr/bin/env bash
# Path guiding (issue 29 item 4): Blender Cycles with its Open PGL path guiding off and on
# (surface guiding, Cycles' default 128 training "samples", which are guiding-field updates of
# at most 4 spp each: it trains through the first 512 spp, during the render, and keeps those
# samples in the image) on the held-out indirect-only box (indirect_box.json), next to
# Mitsuba 3 (llvm_ad_rgb path) and Lightpath --guiding off and on, all at max depth 8 and
# 2 threads. Per spp and seed the renderers alternate: cycles_off, cycles_on, mitsuba,
# lightpath_off, lightpath_on. Seconds: Cycles' and Mitsuba's best wall of 2 renders in one
# process (their RESULT lines; Cycles' includes scene sync/BVH), Lightpath's printed render
# seconds; CPU seconds (user + sys of the render threads) besides them. The load average is
# logged before every render.
#
# Each renderer's MSE is measured against its own converged image (rendered here when
# missing): Cycles 4096 spp unguided (~4 min idle, 8 min under load), Mitsuba 8192 spp
# (as efficiency.sh makes it), Lightpath 4096 spp unguided. Summary by cycles_guiding.py
# (medians over seeds, efficiency 1/(MSE x s), ratios to Mitsuba, guided/unguided gains,
# and each converged image's mean against Mitsuba's).
#
# Usage: benches/guiding/cycles_guiding.sh OUT LIGHTPATH "SPP..." SEED...
#   e.g. benches/guiding/cycles_guiding.sh /tmp/cyg target/dist/lightpath "64 256" 1 2 3
#   PY311=/path/to/python   a Python with bpy 5.0.1, numpy and OpenEXR (default /work/venv311/bin/python)
#   CYCLES_REF, MITSUBA_REF, LIGHTPATH_REF   existing converged images to use instead
#     (CYCLES_REF_SPP, MITSUBA_REF_SPP, LIGHTPATH_REF_SPP: their spp if not 4096, 8192, 4096)
#   RENDERERS="cycles_off cycles_on mitsuba lightpath_off lightpath_on"   the default list; Cycles
#     variants: cycles_on_nodet (use_deterministic_guiding off, with Developer Extras on: Cycles
#     ignores it otherwise), cycles_on_trainN (guiding_training_samples N, counted in field
#     updates of at most 4 spp each, so the default 128 trains through 512 spp; 0 trains to the
#     last sample), e.g. cycles_on_nodet_train16
#   APPEND=1   add to OUT/results.txt instead of starting it afresh (the summary then covers both)
set -u
out=$1; lp=$2; spps=$3; shift 3
here="$(cd "$(dirname "$0")" && pwd)"
peer="$here/../peer"
py311="${PY311:-/work/venv311/bin/python}"
box_json="$here/indirect_box.json"
box_toml="$here/indirect_box.toml"
mkdir -p "$out"
res="$out/results.txt"
[ "${APPEND:-0}" = 1 ] || : > "$res"
renderers="${RENDERERS:-cycles_off cycles_on mitsuba lightpath_off lightpath_on}"
load() { cut -d' ' -f1-3 /proc/loadavg | tr ' ' '/'; }

cycles_ref="${CYCLES_REF:-$out/cycles_ref.exr}"
if [ ! -f "$cycles_ref" ]; then
  echo "rendering the Cycles reference (4096 spp, unguided) ..." >&2
  "$py311" "$peer/cycles_cornell.py" --json "$box_json" --spp 4096 --max-depth 8 --threads 2 \
    --seed 1000000 --beauty-only --guiding 0 --out "${cycles_ref%.exr}" > "$out/cycles_ref.log" 2>&1
fi
mitsuba_ref="${MITSUBA_REF:-$here/out/indirect_box_ref.exr}"
if [ ! -f "$mitsuba_ref" ]; then
  echo "rendering the Mitsuba reference (8192 spp) ..." >&2
  python3 "$peer/mitsuba_cornell.py" --variant llvm_ad_rgb --json "$box_json" --spp 8192 --pass-spp 256 \
    --max-depth 8 --threads 2 --seed 1000000 --out "${mitsuba_ref%.exr}" > /dev/null
fi
lightpath_ref="${LIGHTPATH_REF:-$out/lightpath_ref.exr}"
if [ ! -f "$lightpath_ref" ]; then
  echo "rendering the Lightpath reference (4096 spp, unguided) ..." >&2
  "$lp" render "$box_toml" --quiet --aovs none --spp 4096 --seed 1000000 --threads 2 --guiding off \
    -o "$lightpath_ref" > /dev/null
fi

for spp in $spps; do
  for i in "$@"; do
    for r in $renderers; do
      img="box_${r}_${spp}_$i"
      l=$(load)
      case $r in
        cycles_*)
          opts="--guiding 0"
          case $r in cycles_on*) opts="--guiding 1" ;; esac
          case $r in *_nodet*) opts="$opts --guiding-deterministic 0" ;; esac
          case $r in *_train[0-9]*) opts="$opts --guiding-training-samples ${r##*_train}" ;; esac
          "$py311" "$peer/cycles_cornell.py" --json "$box_json" --spp "$spp" --max-depth 8 --threads 2 \
            --seed "$i" --repeat 2 --beauty-only $opts --out "$out/$img" > "$out/log.txt" 2>&1
          w=$(sed -n 's/^RESULT.* best_s=\([0-9.]*\).*/\1/p' "$out/log.txt")
          c=$(sed -n 's/^RESULT.* best_cpu_s=\([0-9.]*\).*/\1/p' "$out/log.txt") ;;
        mitsuba)
          python3 "$peer/mitsuba_cornell.py" --variant llvm_ad_rgb --json "$box_json" --spp "$spp" \
            --max-depth 8 --threads 2 --seed "$i" --repeat 2 --out "$out/$img" > "$out/log.txt" 2>&1
          w=$(sed -n 's/^RESULT.* best_s=\([0-9.]*\).*/\1/p' "$out/log.txt")
          c=$(sed -n 's/^RESULT.* best_cpu_s=\([0-9.]*\).*/\1/p' "$out/log.txt") ;;
        lightpath_*)
          /usr/bin/time -f "TIME %U %S" -o "$out/time.txt" "$lp" render "$box_toml" --quiet --aovs none \
            --spp "$spp" --threads 2 --seed "$i" --guiding "${r#lightpath_}" -o "$out/$img.exr" > "$out/log.txt" 2>&1
          w=$(sed -n 's/^.*AOVs: \([0-9.]*\) s,.*/\1/p' "$out/log.txt")
          c=$(awk '/^TIME/{print $2 + $3}' "$out/time.txt") ;;
      esac
      if [ -z "$w" ]; then
        echo "$r spp=$spp seed=$i failed:" >&2; tail -5 "$out/log.txt" >&2; continue
      fi
      echo "RESULT spp=$spp renderer=$r seed=$i wall=$w cpu=${c:-nan} load=$l image=$img.exr" | tee -a "$res"
    done
  done
done
"$py311" "$here/cycles_guiding.py" "$res" "$out" cycles="$cycles_ref@${CYCLES_REF_SPP:-4096}" \
  mitsuba="$mitsuba_ref@${MITSUBA_REF_SPP:-8192}" lightpath="$lightpath_ref@${LIGHTPATH_REF_SPP:-4096}"
