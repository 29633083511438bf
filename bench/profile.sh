#!/bin/sh
# Where haze's time goes on the smoke benchmark (docs/performance.md): perf
# samples (cpu-clock, call graphs) of one render, top functions by self time.
# Not part of make bench. Usage: sh bench/profile.sh build/haze [SPP] [ESTIMATOR]
set -eu
HAZE=$1
SPP=${2:-4}
EST=${3:-jittered}
BENCH=$(cd "$(dirname "$0")" && pwd)
CACHE=$BENCH/cache
mkdir -p "$CACHE"
. "$BENCH/lib.sh"
variant "$CACHE/profile.pbrt" "$BENCH/scenes/smoke.pbrt" "$(integrator "$EST" 1)"
# --stats times every media segment (two clock reads each): profile without it.
"$HAZE" render "$CACHE/profile.pbrt" --spp "$SPP" --threads 2 -o "$CACHE/profile.exr" --stats >"$CACHE/profile-stats.txt" 2>/dev/null
perf record -e cpu-clock -F 999 -g -o "$CACHE/perf.data" -- \
    "$HAZE" render "$CACHE/profile.pbrt" --spp "$SPP" --threads 2 -o "$CACHE/profile.exr" --quiet 2>/dev/null
echo "== haze render --stats"
grep '^stat' "$CACHE/profile-stats.txt"
echo "== perf: self time by function (top 25)"
perf report -i "$CACHE/perf.data" --no-children --sort symbol --stdio 2>/dev/null |
    grep -E '^ +[0-9.]+%' | head -25
echo "== perf: by shared object"
perf report -i "$CACHE/perf.data" --no-children --sort dso --stdio 2>/dev/null | grep -E '^ +[0-9.]+%' | head -8
