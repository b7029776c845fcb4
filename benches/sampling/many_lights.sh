#!/usr/bin/env bash
# Equal-time quality of light selection on scenes/many-lights.toml (issue 11): efficiency
# = 1 / (MSE x CPU seconds) of a build against an older one, at 128², 16 spp, one thread,
# clamps off, for SEEDS seeds each (medians), against a 1024-spp reference of the newer
# build. Run twice: on the scene as it is, and with its 48 lamps hidden from the camera
# (`camera_visible = false`), because the lamps are sub-pixel and bright: most of the
# scene's error at 16 spp is the camera's estimate of how much of a pixel a lamp covers,
# which no light selection touches (also printed: the MSE of `CO`, emission the camera
# sees, against the reference's).
#
# Needs: pip install numpy OpenEXR
# Usage: benches/sampling/many_lights.sh NEW_LIGHTPATH OLD_LIGHTPATH [SEEDS]
#   SPP=64  samples per pixel for both builds (default 16).
#   NEW_ARGS="--spp 256 --min-spp 16 --noise-threshold 0.3"  renders the new build with
#   these sampling flags instead of --spp $SPP (adaptive sampling; the mean of its
#   sampleCount channel is printed).
#   OLD_ARGS  the same for the old build (to compare two adaptive rules).
#   OUT=DIR  where renders and the results go (default benches/sampling/out), so that
#   runs of several builds can share the reference.
# Efficiency is only spp-independent for independent samples (MSE ~ 1/n): Sobol points'
# MSE falls faster, so the new build's efficiency grows with SPP; compare at equal SPP.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${OUT:-$here/out}"
mkdir -p "$out"
new="$1"
old="$2"
seeds="${3:-3}"
scene="$root/scenes/many-lights.toml"
hidden="$out/many-lights-hidden-lamps.toml"
sed 's/^groups = \["lamps"\]$/groups = ["lamps"]\ncamera_visible = false/' "$scene" > "$hidden"
common=(--resolution 128x128 --threads 1 --quiet)
spp_both="${SPP:-16}"
read -r -a new_args <<< "${NEW_ARGS:---spp $spp_both}"
read -r -a old_args <<< "${OLD_ARGS:---spp $spp_both}"
# Builds from before issue 11 have no clamps (nor the flag); later ones are unclamped
# unless a scene asks, and this one does not: the flag only makes sure.
clamp_off() { if "$1" render --help | grep -q -- --clamp-indirect; then echo --clamp-indirect 0; fi; }
for variant in visible hidden; do
  file="$scene"; [ "$variant" = hidden ] && file="$hidden"
  ref="$out/many_${variant}_ref.exr"
  if [ ! -f "$ref" ]; then
    "$new" render "$file" --aovs none --aov "seen=CO" --spp 1024 --resolution 128x128 \
      --clamp-indirect 0 --seed 99 --quiet -o "$ref" >/dev/null
  fi
  for build in new old; do
    bin="$new"; [ "$build" = old ] && bin="$old"
    read -r -a clamp <<< "$(clamp_off "$bin")"
    spp=("${old_args[@]}"); [ "$build" = new ] && spp=("${new_args[@]}")
    for seed in $(seq 1 "$seeds"); do
      img="$out/many_${variant}_${build}_$seed.exr"
      user=$( { /usr/bin/time -f "%U" "$bin" render "$file" --aovs none --aov "seen=CO" \
        "${common[@]}" "${spp[@]}" ${clamp[@]+"${clamp[@]}"} --seed "$seed" -o "$img" >/dev/null; } 2>&1 | tail -1)
      echo "$variant $build $seed $user $img"
    done
  done
done > "$out/many_lights.txt"
python3 - "$out" <<'PY'
import statistics, sys
import numpy as np
import OpenEXR

out = sys.argv[1]

def rgb(path, name):
    with OpenEXR.File(path, separate_channels=False) as f:
        return np.asarray(f.channels()[name].pixels, dtype=np.float64)[..., :3]

def mean_spp(path):
    """The mean of the sampleCount channel (adaptive sampling), else None."""
    with OpenEXR.File(path, separate_channels=True) as f:
        channels = f.channels()
        if "sampleCount" not in channels:
            return None
        return float(np.mean(np.asarray(channels["sampleCount"].pixels, dtype=np.float64)))

runs = {}
for line in open(f"{out}/many_lights.txt"):
    variant, build, seed, user, img = line.split()
    ref = f"{out}/many_{variant}_ref.exr"
    mse = np.mean((rgb(img, "RGBA") - rgb(ref, "RGBA")) ** 2)
    seen = np.mean((rgb(img, "seen") - rgb(ref, "seen")) ** 2)
    runs.setdefault((variant, build), []).append((float(user), mse, seen, mean_spp(img)))
for variant in ("visible", "hidden"):
    eff = {}
    for build in ("old", "new"):
        rs = runs[(variant, build)]
        t = statistics.median(r[0] for r in rs)
        mse = statistics.median(r[1] for r in rs)
        seen = statistics.median(r[2] for r in rs)
        eff[build] = 1 / (mse * t)
        spps = [r[3] for r in rs if r[3] is not None]
        spp = f"  mean spp {statistics.median(spps):.1f}" if spps else ""
        print(f"lamps {variant:7} {build}: user {t:.2f} s  MSE {mse:.4e} (camera-seen emission "
              f"{seen:.4e})  efficiency {eff[build]:.1f}{spp}  ({len(rs)} runs)")
    print(f"lamps {variant:7} new / old efficiency: {eff['new'] / eff['old']:.2f}x")
PY
