# Sourced by modes.sh, media.sh and caustic.sh: one timed 64-spp render for modes.py.
#   timed_mode OUT LIGHTPATH SCENE MODE SEED FILE [RENDER ARGS...]
# renders FILE with --guiding MODE to OUT/SCENE_MODE_SEED.exr (2 threads, no AOVs) and
# appends "RESULT scene=SCENE renderer=MODE seed=SEED wall=… cpu=… image=…" to
# OUT/results.txt: Lightpath's wall seconds and /usr/bin/time's user + sys.
timed_mode() {
  local out=$1 lp=$2 scene=$3 mode=$4 seed=$5 file=$6
  shift 6
  /usr/bin/time -f "TIME %U %S" -o "$out/time.txt" "$lp" render "$file" "$@" --quiet --aovs none \
    --spp 64 --threads 2 --seed "$seed" --guiding "$mode" -o "$out/${scene}_${mode}_$seed.exr" \
    > "$out/log.txt" 2>&1
  local w c
  w=$(sed -n 's/^.*AOVs: \([0-9.]*\) s,.*/\1/p' "$out/log.txt")
  c=$(awk '/^TIME/{print $2 + $3}' "$out/time.txt")
  echo "RESULT scene=$scene renderer=$mode seed=$seed wall=$w cpu=$c image=${scene}_${mode}_$seed.exr" \
    >> "$out/results.txt"
}
