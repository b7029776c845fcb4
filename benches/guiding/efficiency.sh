#!/usr/bin/env bash
# Path guiding (issue 29): efficiency = 1 / (MSE x seconds, training included) with
# --guiding off, on and auto, on
#   indirect-box    the held-out scene (make_indirect_box.py): Cornell box lit only by a
#                   lamp facing the ceiling above a baffle; also Mitsuba 3 llvm_ad_rgb
#                   path at the same spp; reference: Mitsuba, 8192 spp (2048 spp's own noise was 12 % of Lightpath's error);
#   cornell-classic the peer Cornell box (reference ../peer/ref/cornell_ref.exr);
#   room            the tuning scene (room.toml, the tests' scene); reference rendered
#                   here by Lightpath unguided at 1024 spp.
#   cornell         the built-in scene nobody tuned guiding on (reference: Lightpath
#                   unguided, 1024 spp).
# Summary by ../peer/efficiency.py (medians over repeats; ratios of lightpath (off),
# lightpath_guided (on) and lightpath_auto to the others).
#
# Usage: benches/guiding/efficiency.sh [SPP] [REPEATS] [PASSES]   (defaults 64, 3, 4)
#   LIGHTPATH=/path/to/lightpath  times that binary instead of building the dist profile.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"
spp="${1:-64}"
repeats="${2:-3}"
passes="${3:-4}"
if [ -n "${LIGHTPATH:-}" ]; then
  lightpath="$LIGHTPATH"
else
  cargo build --profile dist --manifest-path "$root/Cargo.toml" >/dev/null
  lightpath="${CARGO_TARGET_DIR:-$root/target}/dist/lightpath"
fi
seconds() { sed -n 's/^.*AOVs: \([0-9.]*\) s,.*/\1/p'; }

box_ref="$out/indirect_box_ref.exr"
if [ ! -f "$box_ref" ]; then
  echo "rendering the indirect-box reference (Mitsuba, 8192 spp, ~2.5 min) ..." >&2
  python3 "$here/../peer/mitsuba_cornell.py" --variant llvm_ad_rgb --json "$here/indirect_box.json" \
    --spp 8192 --pass-spp 256 --max-depth 8 --threads 2 --seed 1000000 \
    --out "$out/indirect_box_ref" >/dev/null
fi
cornell_ref="$out/cornell_builtin_ref.exr"
if [ ! -f "$cornell_ref" ]; then
  echo "rendering the cornell reference (Lightpath unguided, 1024 spp) ..." >&2
  "$lightpath" render cornell --quiet --aovs none --spp 1024 --seed 99 --threads 2 \
    --guiding off -o "$cornell_ref" >/dev/null
fi
room_ref="$out/room_ref.exr"
if [ ! -f "$room_ref" ]; then
  echo "rendering the room reference (Lightpath unguided, 1024 spp) ..." >&2
  "$lightpath" render "$here/room.toml" --quiet --aovs none --spp 1024 --seed 99 --threads 2 \
    --guiding off -o "$room_ref" >/dev/null
fi

results="$out/efficiency.txt"
: > "$results"
for i in $(seq 1 "$repeats"); do
  python3 "$here/../peer/mitsuba_cornell.py" --variant llvm_ad_rgb --json "$here/indirect_box.json" \
      --spp "$spp" --max-depth 8 --threads 2 --seed "$i" --repeat 2 --out "$out/box_mitsuba_$i" \
    | sed -n "s/^RESULT.* best_s=\([0-9.]*\).*/RESULT scene=indirect-box renderer=mitsuba_llvm_ad_rgb seconds=\1 image=box_mitsuba_$i.exr/p" >> "$results"
  for scene in indirect-box cornell-classic room cornell; do
    case "$scene" in
      indirect-box) file="$here/indirect_box.toml" ;;
      cornell-classic) file=cornell-classic ;;
      room) file="$here/room.toml" ;;
      cornell) file=cornell ;;
    esac
    # Alternating the modes within a repeat spreads the machine's load over all three.
    for g in off on auto; do
      case "$g" in
        off) name=lightpath ;;
        on) name=lightpath_guided ;;
        auto) name=lightpath_auto ;;
      esac
      t=$("$lightpath" render "$file" --quiet --aovs none --spp "$spp" --threads 2 --seed "$i" \
          --guiding "$g" --guiding-passes "$passes" -o "$out/${scene}_${name}_$i.exr" | seconds)
      echo "RESULT scene=$scene renderer=$name seconds=$t image=${scene}_${name}_$i.exr" >> "$results"
    done
  done
done
cat "$results"
python3 "$here/../peer/efficiency.py" "$results" "$out" indirect-box="$box_ref" \
  cornell-classic="$here/../peer/ref/cornell_ref.exr" room="$room_ref" cornell="$cornell_ref"
