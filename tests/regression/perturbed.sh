#!/bin/sh
# The regression check must catch a real change: render SCENE with one light
# 5% brighter (the sed expression EDIT applied to the scene text) at the
# suite's low spp and require `haze diff --ztest` against the reference to fail
# (exit 1; 0 means the change went unnoticed, 2 an error).
#   usage: perturbed.sh HAZE SCENE.pbrt REF.exr OUTDIR EDIT [SPP] [SEED]
set -eu
haze=$1 scene=$2 ref=$3 outdir=$4 edit=$5 spp=${6:-16} seed=${7:-1}
name=$(basename "$scene" .pbrt)
mkdir -p "$outdir"
# The edited scene sits next to the original, so relative paths still resolve.
edited="$(dirname "$scene")/.perturbed-$name-$$.pbrt"
trap 'rm -f "$edited"' EXIT
sed "$edit" "$scene" > "$edited"
if cmp -s "$scene" "$edited"; then
    echo "$name: the edit '$edit' changed nothing" >&2
    exit 2
fi
out="$outdir/$name.perturbed.exr"
"$haze" render "$edited" --spp "$spp" --seed "$seed" --quiet -o "$out"
status=0
"$haze" diff "$out" "$ref" --ztest || status=$?
if [ "$status" -ne 1 ]; then
    echo "$name: a light 5% brighter was not caught (haze diff exit $status)" >&2
    exit 1
fi
echo "$name: a light 5% brighter is caught"
