#!/bin/sh
# Renders every scene of scenes/, tests/regression/scenes and bench/scenes (the
# bench scenes under each integrator and estimator the bench uses) at a few
# samples per pixel and prints one "sha256  name" line per image. Run it before
# and after a change that must not alter images, and diff the two listings:
#   sh tools/image-hashes.sh build/haze > before.txt   (... change, rebuild ...)
#   sh tools/image-hashes.sh build/haze > after.txt && diff before.txt after.txt
# HASH_SPP (default 2) sets the samples. Scratch files go to bench/cache/hashes
# and the bench scenes' wrappers to bench/cache (their volumes' relative paths
# resolve from the top scene's folder, as under bench/run.sh).
set -eu
HAZE=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
TOP=$(cd "$(dirname "$0")/.." && pwd)
SPP=${HASH_SPP:-2}
OUT=$TOP/bench/cache/hashes
mkdir -p "$OUT"

render() { # NAME SCENE [ARGS...]
    name=$1 scene=$2
    shift 2
    "$HAZE" render "$scene" --quiet --threads 2 --seed 3 -o "$OUT/$name.exr" "$@" \
        >"$OUT/$name.log" 2>&1 || { echo "FAILED  $name"; return 0; }
    echo "$(sha256sum <"$OUT/$name.exr" | cut -d' ' -f1)  $name"
}

for f in "$TOP"/scenes/*.pbrt; do
    render "scenes-$(basename "$f" .pbrt)" "$f" --spp "$SPP"
done
for f in "$TOP"/tests/regression/scenes/*.pbrt; do
    render "regression-$(basename "$f" .pbrt)" "$f" --spp "$SPP"
done

# The bench scenes carry no Integrator: each variant is a wrapper that names
# one and Includes the scene by a relative path (the EXR header's haze:render
# id hashes the bytes of every file read, so an absolute path would make the
# hashes depend on where the checkout lives).
variants='default|Integrator "singlescatter"
raymarch|Integrator "singlescatter" "string transmittance" "raymarch" "float stepsize" 2
ratio|Integrator "singlescatter" "string transmittance" "ratio"
residual|Integrator "singlescatter" "string transmittance" "residual"
mixed|Integrator "singlescatter" "string transmittance" "raymarch" "string shadowtransmittance" "ratio" "integer lightsamples" 2
volpath1|Integrator "volpath" "integer maxdepth" 1
volpath8|Integrator "volpath" "integer maxdepth" 8'
for f in "$TOP"/bench/scenes/*.pbrt; do
    base=$(basename "$f" .pbrt)
    echo "$variants" | while IFS='|' read -r v line; do
        w="$TOP/bench/cache/hash-$base-$v.pbrt"
        printf '%s\nInclude "../scenes/%s"\n' "$line" "$(basename "$f")" >"$w"
        render "bench-$base-$v" "$w" --spp "$SPP"
    done
done
# The step pilot and adaptive sampling.
w="$TOP/bench/cache/hash-smoke-target.pbrt"
printf 'Integrator "singlescatter"\nInclude "../scenes/smoke.pbrt"\n' >"$w"
render bench-smoke-target "$w" --target-error 1e-2 --spp 8
w="$TOP/bench/cache/hash-smoke-cache.pbrt"
printf 'Integrator "singlescatter" "float shadowcache" 1\nInclude "../scenes/smoke.pbrt"\n' >"$w"
render bench-smoke-cache "$w" --spp "$SPP"
# volpath's knobs together (the shadow cache, marching, splitting).
w="$TOP/bench/cache/hash-cloud-knobs.pbrt"
printf 'Integrator "volpath" "integer maxdepth" 16 "float shadowcache" 1 "float stepsize" 2 "integer mediumsplits" 3\nInclude "../scenes/cloud.pbrt"\n' >"$w"
render bench-cloud-knobs "$w" --spp "$SPP"
