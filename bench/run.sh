#!/bin/sh
# make bench: the speed/accuracy ladder, the vdb_render peer, the yardsticks,
# then bench/results/trade.md and trade.png (bench/README.md).
# Usage: sh bench/run.sh BUILD/haze     (BENCH_QUICK=1: the ~3 min smoke run,
# written to bench/cache/quick-results/ so the committed results stay;
# BENCH_PARTS="peer yardsticks" runs only those parts)
set -eu
HAZE=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
BENCH=$(cd "$(dirname "$0")" && pwd)
CACHE=$BENCH/cache
THREADS=${BENCH_THREADS:-2}
# The compiled helpers of bench/CMakeLists.txt, next to haze in its build tree.
EXR_EXTRAPOLATE=${EXR_EXTRAPOLATE:-$(dirname "$HAZE")/bench/exr_extrapolate}
BENCH_QUICK=${BENCH_QUICK:-}
RESULTS=$BENCH/results
[ -n "$BENCH_QUICK" ] && RESULTS=$CACHE/quick-results
mkdir -p "$CACHE" "$RESULTS"
LOG=$CACHE/bench.log
: >"$LOG"
BENCH_LOAD=$(cut -d' ' -f1-3 /proc/loadavg)

. "$BENCH/lib.sh"
. "$BENCH/ladder.sh"
. "$BENCH/peer.sh"
. "$BENCH/yardsticks.sh"
. "$BENCH/bounce.sh"
. "$BENCH/target.sh"
. "$BENCH/scale.sh"
. "$BENCH/bigcloud.sh"
. "$BENCH/spectral.sh"
. "$BENCH/cycles.sh"
. "$BENCH/report.sh"

# BENCH_PARTS: a subset of "ladder peer bounce target yardsticks scale bigcloud spectral cycles"
# (the others' tables of the last run are reused by the report). The scale, bigcloud, spectral
# and cycles parts write their own scale.md, bigcloud.md, spectral.md and cycles.md; trade.md
# is written when any other part ran. cycles (Blender's Cycles, a bench tool to install by
# hand) runs only when named.
PARTS=${BENCH_PARTS-ladder peer bounce target yardsticks scale bigcloud spectral}
start=$(now)
for part in $PARTS; do
    echo "bench: $part" >&2
    "${part}_run"
done
case " $PARTS " in
*" ladder "* | *" peer "* | *" bounce "* | *" target "* | *" yardsticks "*)
    report_run
    echo "bench: done in $(elapsed "$start" "$(now)") s: $RESULTS/trade.md, $RESULTS/trade.png" >&2 ;;
*) echo "bench: done in $(elapsed "$start" "$(now)") s" >&2 ;;
esac
