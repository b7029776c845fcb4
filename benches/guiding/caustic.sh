#!/usr/bin/env bash
# Guiding on a caustic through rough (regularised) glass (issue 29, hard scenes):
# --guiding off, auto and on on the tuning stand-in caustic.toml and the held-out
# caustic_heldout.toml, alternating per seed, CPU seconds (user + sys) and MSE against
# an unguided 4096-spp reference (seed 99, rendered here once). modes.py summarises.
# Findings: CAUSTIC.md.
#
# Usage: benches/guiding/caustic.sh OUT LIGHTPATH SEED...
set -u
out=$1; lp=$2; shift 2
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=timed_mode.sh
. "$here/timed_mode.sh"
mkdir -p "$out"
res="$out/results.txt"
: > "$res"
for scene in caustic caustic_heldout; do
  if [ ! -f "$out/${scene}_ref.exr" ]; then
    "$lp" render "$here/$scene.toml" --quiet --aovs none --spp 4096 --seed 99 --threads 2 \
      --guiding off -o "$out/${scene}_ref.exr" > /dev/null
  fi
done
for i in "$@"; do
  for scene in caustic caustic_heldout; do
    for g in off auto on; do
      timed_mode "$out" "$lp" "$scene" "$g" "$i" "$here/$scene.toml"
    done
  done
done
uptime
python3 "$here/modes.py" "$out" caustic="$out/caustic_ref.exr" caustic_heldout="$out/caustic_heldout_ref.exr"
