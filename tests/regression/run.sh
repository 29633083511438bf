#!/bin/sh
# One regression check, run by ctest: render SCENE at low spp with a seed other
# than the reference's, twice (2 threads, then 1: explicit, so that the check
# means the same on a one-core machine), require the two files to be byte-identical
# (same scene and seed, same image), then require `haze diff --ztest` against
# the reference EXR to pass.
#   usage: run.sh HAZE SCENE.pbrt REF.exr OUTDIR [SPP] [SEED]
set -eu
haze=$1 scene=$2 ref=$3 outdir=$4 spp=${5:-16} seed=${6:-1}
name=$(basename "$scene" .pbrt)
mkdir -p "$outdir"
a="$outdir/$name.a.exr"
b="$outdir/$name.b.exr"
"$haze" render "$scene" --spp "$spp" --seed "$seed" --quiet --threads 2 -o "$a"
"$haze" render "$scene" --spp "$spp" --seed "$seed" --quiet --threads 1 -o "$b"
if ! cmp -s "$a" "$b"; then
    echo "$name: two renders with seed $seed differ (2 threads vs 1)" >&2
    exit 1
fi
if [ ! -f "$ref" ]; then
    echo "$name: no reference $ref (make update-refs writes it)" >&2
    exit 1
fi
"$haze" diff "$a" "$ref" --ztest
