#!/usr/bin/env bash
# Path guiding in media (issue 29): --guiding off, on and auto at 64 spp on scenes with
# participating media, alternating per seed, CPU seconds (user + sys) beside Lightpath's
# wall seconds; each against a Lightpath unguided reference of REF_SPP (default 2048)
# samples rendered here once. Scenes:
#   fog_door   benches/guiding/fog_door.toml: door.toml filled with fog (the one looked at
#              while writing medium guiding)
#   hazy_box   benches/guiding/hazy_box.toml: the indirect box in haze (held out)
#   fog_disk   benches/media/equiangular/fog_disk_heldout.toml (held out)
#   smoke      scenes/smoke.toml at 128 x 128 (held out: a grid medium)
# Summary by modes.py (medians over seeds).
#
# Usage: benches/guiding/media.sh OUT LIGHTPATH SEED...
set -u
out=$1; lp=$2; shift 2
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=timed_mode.sh
. "$here/timed_mode.sh"
root="$(cd "$here/../.." && pwd)"
ref_spp="${REF_SPP:-2048}"
mkdir -p "$out"
res="$out/results.txt"
: > "$res"
scene_file() {
  case $1 in
    fog_door) echo "$here/fog_door.toml" ;;
    hazy_box) echo "$here/hazy_box.toml" ;;
    fog_disk) echo "$root/benches/media/equiangular/fog_disk_heldout.toml" ;;
    smoke) echo "$root/scenes/smoke.toml" ;;
  esac
}
scene_args() {
  case $1 in
    smoke) echo "--resolution 128x128" ;;
    *) echo "" ;;
  esac
}
scenes="${SCENES:-fog_door hazy_box fog_disk smoke}"
refs=()
for scene in $scenes; do
  ref="$out/${scene}_ref.exr"
  if [ ! -f "$ref" ]; then
    # shellcheck disable=SC2046
    "$lp" render "$(scene_file "$scene")" $(scene_args "$scene") --quiet --aovs none \
      --spp "$ref_spp" --seed 99 --threads 2 --guiding off -o "$ref" > /dev/null
  fi
  refs+=("$scene=$ref")
done
for i in "$@"; do
  for scene in $scenes; do
    for g in off on auto; do
      # shellcheck disable=SC2046
      timed_mode "$out" "$lp" "$scene" "$g" "$i" "$(scene_file "$scene")" $(scene_args "$scene")
    done
  done
done
python3 "$here/modes.py" "$out" "${refs[@]}"
