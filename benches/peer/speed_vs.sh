#!/usr/bin/env bash
# Render speed of two builds of Lightpath on one scene, alternating runs so that the
# machine's drift (±15 % over an hour here) falls on both alike; prints each run's
# samples/s and the ratio of the medians. Issue 26 asks that OpenPBR keeps
# cornell-classic within 3 % of main at daac349 built with the same profile:
#   git worktree add /tmp/base daac349 && (cd /tmp/base && cargo build --release)
#   benches/peer/speed_vs.sh /tmp/base/target/release/lightpath target/release/lightpath
set -euo pipefail
base="$1"; new="$2"; scene="${3:-cornell-classic}"; runs="${RUNS:-5}"; spp="${SPP:-64}"
dir="$(mktemp -d)"
rate() { "$1" render "$scene" --spp "$spp" -o "$dir/out.exr" 2>&1 | grep -o '[0-9.]* M samples/s' | head -1 | cut -d' ' -f1; }
a=(); b=()
for i in $(seq "$runs"); do
  a+=("$(rate "$base")"); b+=("$(rate "$new")")
  echo "run $i: base ${a[-1]} M samples/s, new ${b[-1]} M samples/s"
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END {print (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'; }
ma="$(median "${a[@]}")"; mb="$(median "${b[@]}")"
echo "median: base $ma, new $mb M samples/s; new/base = $(awk -v a="$ma" -v b="$mb" 'BEGIN {printf "%.3f", b/a}')"
rm -rf "$dir"
