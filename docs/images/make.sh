#!/bin/sh
# Regenerates every picture in docs/ from today's defaults: the AOV pictures of
# docs/aovs.md, the examples of docs/lpe.md (docs/images/lpe/), the denoising pictures
# (with a binary built with the `denoise` feature) and the viewer's screenshots (with
# node and a headless chromium).
#
#   docs/images/make.sh                      # uses target/release/lightpath, else target/debug
#   LIGHTPATH=path/to/lightpath THREADS=1 docs/images/make.sh
#
# Each step prints what it made, or why it was skipped; a picture over 60 KB is reported.
set -eu
cd "$(dirname "$0")/../.."
if [ -z "${LIGHTPATH:-}" ]; then
    if [ -x target/release/lightpath ]; then LIGHTPATH=target/release/lightpath
    else LIGHTPATH=target/debug/lightpath; fi
fi
[ -x "$LIGHTPATH" ] || { echo "no binary at $LIGHTPATH: cargo build -p lightpath first" >&2; exit 1; }
case "$LIGHTPATH" in /*) ;; *) LIGHTPATH="$PWD/$LIGHTPATH" ;; esac
threads=""
[ -n "${THREADS:-}" ] && threads="--threads $THREADS"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
lp() { "$LIGHTPATH" "$@"; }

# comp EXR NAME EXPRESSION [comp options…]: writes docs/images/<NAME>.png from an AOV sum.
comp() {
    exr=$1 name=$2 expression=$3
    shift 3
    lp comp "$exr" "$expression" -o "$work/out.exr" "$@" > /dev/null
    mv "$work/out.png" "docs/images/$name.png"
}

echo "== docs/aovs.md: the built-in cornell, 200x200, 256 spp"
# shellcheck disable=SC2086
lp render cornell --spp 256 --resolution 200x200 --light-groups --bounces 2 $threads -q \
    --aov "scatterCube=C<[RT][DS]'scatterCube'>.*[<L.>O]" \
    --aov "cubeToWall=C<..'scatterCube'>+<..'rightWall'>[<L.>O]" \
    --aov "caustics=C<RD>[S]+[<L.>O]" \
    --aov "keyShadows=shadows;C<RD><L.'key'>" -o "$work/cornell.exr"
for aov in beauty emission directDiffuse indirectDiffuse directSpecular indirectSpecular \
    subsurface transmissive albedo beauty_key beauty_fill beauty__default \
    scatterCube cubeToWall caustics keyShadows bounce0 bounce1 bounce2plus; do
    comp "$work/cornell.exr" "$aov" "$aov"
done
lp comp "$work/cornell.exr" -o "$work/out.exr" --gain key=0.25 --gain fill=6 > /dev/null
mv "$work/out.png" docs/images/relit_gains.png
comp "$work/cornell.exr" red_caustics "beauty - caustics + (1,0.3,0.3)*caustics"

echo "== docs/lpe.md: the examples on the built-in cornell, 160x160, 256 spp"
mkdir -p docs/images/lpe
# name|definition: each example of docs/lpe.md#examples, in its order.
cat > "$work/examples.txt" <<'EXAMPLES'
beauty|lpe:beauty
directDiffuse|C<RD>[<L.>O]
indirectDiffuse|C<RD>[DS]+[<L.>O]
emissive|C[<L.>O]
caustics|CDS+[<L.>O]
diffuseNoCaustics|C<RD>D[DS]*[<L.>O]
diffuseLobe|CD2[<L.>O]
roughSpecularLobe|CS3[DS]*[<L.>O]
glassReflection|C<RS8>[DS]*[<L.>O]
glassTransmission|C<TS8>[DS]*[<L.>O]
subsurfaceLobe|CD3[DS]*[<L.>O]
keyLight|C[DS]*[<L.'key'><O'key'>]
keyOrFill|C[DS]*<L.('key'|'fill')>
floorDiffuse|C<RD'floor'>[<L.>O]
exceptFloor|C<RD[^'floor']>[<L.>O]
floorShadows|shadows;C<.[DS].'floor'><L.>
unoccludedKey|unoccluded;C<RD><L.'key'>
secondBounce|C<.>{2}[<L.>O]
upToTwo|C<.>{,2}[<L.>O]
throughGlass|C<TS8>+<RD>[<L.>O]
albedo|lpe:albedo
secondAlbedo|nothruput;overwrite;C<RD><RU2>L
EXAMPLES
# shellcheck disable=SC2086
set -- render cornell --spp 256 --resolution 160x160 -q --aovs none $threads -o "$work/lpe.exr"
while IFS= read -r line; do
    set -- "$@" --aov "${line%%|*}=${line#*|}"
done < "$work/examples.txt"
lp "$@"
while IFS= read -r line; do
    name=${line%%|*}
    exposure=0
    case $name in caustics | glassReflection) exposure=2 ;; esac  # dim: 2 stops brighter
    lp comp "$work/lpe.exr" "$name" -o "$work/out.exr" --exposure $exposure > /dev/null
    mv "$work/out.png" "docs/images/lpe/$name.png"
done < "$work/examples.txt"

echo "== docs/lpe.md: a holdout (the floor of cornell as a shadow catcher), 160x160, 256 spp"
sed '/^name = "floor"/a holdout = true' scenes/cornell.toml > "$work/holdout.toml"
# shellcheck disable=SC2086
lp render "$work/holdout.toml" --spp 256 --resolution 160x160 -q --aovs none $threads \
    --aov "occluded=holdouts;C<RD>[<L.>O]" \
    --aov "unoccluded=holdouts;unoccluded;C<RD>[<L.>O]" -o "$work/holdout.exr"
for aov in beauty occluded unoccluded shadow; do
    lp comp "$work/holdout.exr" "$aov" -o "$work/out.exr" > /dev/null
    mv "$work/out.png" "docs/images/lpe/holdout_$aov.png"
done

echo "== docs/aovs.md: denoising, cornell 200x200 at 16 spp"
if lp render cornell --spp 1 --resolution 8x8 -q --denoise -o "$work/probe.exr" > /dev/null 2>&1; then
    # shellcheck disable=SC2086
    lp render cornell --spp 16 --resolution 200x200 --light-groups -q $threads -o "$work/noisy.exr"
    lp denoise "$work/noisy.exr" -o "$work/denoised.exr" --keep-noisy > /dev/null
    for aov in beauty indirectDiffuse beauty_key; do
        comp "$work/denoised.exr" "denoise_$aov" "$aov"
        comp "$work/denoised.exr" "denoise_${aov}_noisy" "${aov}_noisy"
    done
    comp "$work/denoised.exr" denoise_specular specular --exposure 3
    comp "$work/denoised.exr" denoise_specular_noisy specular_noisy --exposure 3
else
    echo "skipped: $LIGHTPATH has no denoiser (build it with --features denoise, docs/aovs.md)"
fi

echo "== docs/aovs.md: the viewer's screenshots"
chromium=${CHROMIUM:-/usr/bin/chromium}
if command -v node > /dev/null && [ -x "$chromium" ]; then
    LIGHTPATH="$LIGHTPATH" CHROMIUM="$chromium" node tests/browser/view.mjs --screenshots docs/images
else
    echo "skipped: needs node and a headless chromium at \$CHROMIUM (apt-get install chromium)"
fi

for png in docs/images/*.png docs/images/lpe/*.png; do
    size=$(wc -c < "$png")
    [ "$size" -le 61440 ] || echo "note: $png is $size bytes (over 60 KB)"
done
echo "done"
