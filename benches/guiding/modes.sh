#!/usr/bin/env bash
# Path guiding (issue 29): --guiding off, on and auto on the held-out indirect box, the
# tuning room, cornell-classic and the held-out door.toml (a room lit through a door;
# reference: Lightpath unguided, 1024 spp, rendered here), alternating per seed, with CPU seconds (user + sys)
# besides Lightpath's wall seconds, and Mitsuba 3 llvm_ad_rgb on the box (best wall of 2).
# References as efficiency.sh makes them (run it once first, or render them the same way).
#
# Usage: benches/guiding/modes.sh OUT LIGHTPATH SEED...
set -u
out=$1; lp=$2; shift 2
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=timed_mode.sh
. "$here/timed_mode.sh"
mkdir -p "$out"
res="$out/results.txt"
: > "$res"
door_ref="$here/out/door_ref.exr"
if [ ! -f "$door_ref" ]; then
  "$lp" render "$here/door.toml" --quiet --aovs none --spp 1024 --seed 99 --threads 2 \
    --guiding off -o "$door_ref" > /dev/null
fi
for i in "$@"; do
  python3 "$here/../peer/mitsuba_cornell.py" --variant llvm_ad_rgb --json "$here/indirect_box.json" \
      --spp 64 --max-depth 8 --threads 2 --seed "$i" --repeat 2 --out "$out/box_mitsuba_$i" \
    | sed -n "s/^RESULT.* best_s=\([0-9.]*\).*/RESULT scene=box renderer=mitsuba seed=$i wall=\1 cpu=nan image=box_mitsuba_$i.exr/p" >> "$res"
  for scene in box room cornell-classic door; do
    case $scene in
      box) f="$here/indirect_box.toml" ;;
      room) f="$here/room.toml" ;;
      door) f="$here/door.toml" ;;
      *) f=cornell-classic ;;
    esac
    for g in off on auto; do
      timed_mode "$out" "$lp" "$scene" "$g" "$i" "$f"
    done
  done
done
python3 "$here/modes.py" "$out" box="$here/out/indirect_box_ref.exr" room="$here/out/room_ref.exr" \
  cornell-classic="$here/../peer/ref/cornell_ref.exr" door="$door_ref"
