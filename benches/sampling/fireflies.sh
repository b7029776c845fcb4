#!/usr/bin/env bash
# Fireflies on the built-in `cornell` at its default settings (issue 11): renders it
# (320², 32 spp) with seeds 0..N-1 and counts isolated outlier pixels with
# fireflies.py (luminance > 3x the median of the 8 neighbours, no neighbour an outlier),
# then prints where the isolated ones come from (their excess over the neighbours'
# median, per AOV) for the first seed.
#
# Needs: pip install numpy OpenEXR
# Usage: benches/sampling/fireflies.sh [SEEDS] [extra render arguments...]
#   LIGHTPATH=/path/to/lightpath  uses that binary (default: a release build of this tree)
#   e.g. fireflies.sh 3 --regularize 0.6    (the defaults of the previous session)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$here/out"
mkdir -p "$out"
seeds="${1:-3}"
shift || true
if [ -z "${LIGHTPATH:-}" ]; then
  cargo build --profile dist --manifest-path "$root/Cargo.toml" >/dev/null
  LIGHTPATH="${CARGO_TARGET_DIR:-$root/target}/release/lightpath"
fi
for seed in $(seq 0 $((seeds - 1))); do
  "$LIGHTPATH" render cornell --quiet --seed "$seed" "$@" -o "$out/cornell_$seed.exr" >/dev/null
  python3 "$here/fireflies.py" "$out/cornell_$seed.exr"
done
# Where they come from: glows reached after a scatter, caustics through the glass ball,
# paths over the metal ball, and all light from the key.
"$LIGHTPATH" render cornell --quiet --seed 0 "$@" --aovs none \
  --aov "glow=C.+O" --aov "glassCaustic=C<RD>.*<.S'glassBall'>.*L" \
  --aov "metal=C.*<.S'metalBall'>.*L" --aov "key=C.*<L.'key'>" \
  -o "$out/cornell_sources.exr" >/dev/null
python3 "$here/fireflies.py" --aov glow --aov glassCaustic --aov metal --aov key \
  "$out/cornell_sources.exr"
