#!/bin/sh
# One image across MPI ranks: wall time for 1, 2 and 4 ranks on one scene,
# with cores/ranks threads per rank and with all threads per rank; the time
# rank 0 spends waiting for the other ranks and gathering; the mean wait for a
# tile index; scaling efficiency; the per-tile overhead; and what a plain
# `haze render` saves by not starting MPI. Every MPI image is checked against
# the single-process image byte for byte. Writes bench/results/mpi.md.
#
#   sh bench/mpi_scaling.sh [HAZE] [SCENE] [SPP]
#   (defaults: build/haze scenes/smoke.pbrt 16; REPEAT=2 runs each, best kept)
set -eu

HAZE=${1:-build/haze}
SCENE=${2:-scenes/smoke.pbrt}
SPP=${3:-16}
REPEAT=${REPEAT:-2}
OUT=${OUT:-bench/results/mpi.md}
MPIRUN=${MPIRUN:-mpirun}
CORES=$(nproc)
SEED=1
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT INT TERM
# CI and containers run as root; OpenMPI refuses that unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

command -v "$MPIRUN" >/dev/null || { echo "mpi_scaling: $MPIRUN not found" >&2; exit 1; }
[ -x "$HAZE" ] || { echo "mpi_scaling: $HAZE is not built" >&2; exit 1; }
mkdir -p "$(dirname "$OUT")"

now() { date +%s.%N; }
# CPU seconds (user + system) of all reaped children so far, the ranks that
# mpirun reaps included: the second line of `times`, which must run in this
# shell (not in a $(...) subshell, whose children are its own).
child_cpu() {
    times >"$WORK/times"
    sed -n 2p "$WORK/times" | awk '{
        t = 0
        for (i = 1; i <= 2; i++) { split($i, p, "m"); sub("s", "", p[2]); t += p[1] * 60 + p[2] }
        printf "%.3f\n", t }' >"$WORK/cpu.$1"
}

# best_of CMD...: runs CMD REPEAT times, keeps the output of the fastest run
# in $WORK/best.log, its CPU seconds (all processes) in $WORK/best.cpu, and
# prints its wall time (seconds, process start to exit). Called directly, not
# in $(...), so that `times` sees the children.
best_of() {
    best=
    i=0
    while [ "$i" -lt "$REPEAT" ]; do
        child_cpu 0
        t0=$(now)
        "$@" >"$WORK/run.log" 2>&1 || { cat "$WORK/run.log" >&2; exit 1; }
        t1=$(now)
        child_cpu 1
        c0=$(cat "$WORK/cpu.0")
        c1=$(cat "$WORK/cpu.1")
        t=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
        if [ -z "$best" ] || [ "$(awk -v t="$t" -v b="$best" 'BEGIN { print (t < b) }')" = 1 ]; then
            best=$t
            cp "$WORK/run.log" "$WORK/best.log"
            awk -v a="$c0" -v b="$c1" 'BEGIN { printf "%.2f\n", b - a }' >"$WORK/best.cpu"
        fi
        i=$((i + 1))
    done
    printf '%.2f\n' "$best" >"$WORK/best.wall"
}
wall_of() { cat "$WORK/best.wall"; }
cpu_of() { cat "$WORK/best.cpu"; }

# Fields of the report line "N ranks: tiles a + b (rank 0 first); a tile index
# took X us per remote claim (K claims); rank 0 waited W s ..., gather G s".
field() { sed -n "s/.*$1.*/\\1/p" "$WORK/best.log" | head -n 1; }

echo "mpi_scaling: $SCENE at $SPP spp, $CORES cores, best of $REPEAT" >&2
ref="$WORK/single.exr"
load0=$(cut -d' ' -f1-3 /proc/loadavg)
best_of "$HAZE" render "$SCENE" --spp "$SPP" --seed "$SEED" -o "$ref"
t_single=$(wall_of)
c_single=$(cpu_of)
tiles=$(sed -n 's/.*(\([0-9]*\) x \([0-9]*\) pixels rendered.*/\1 \2/p' "$WORK/best.log" |
        awk '{ printf "%d", int(($1 + 15) / 16) * int(($2 + 15) / 16) }')

# Start-up: a plain render of a tiny scene versus the same under mpirun -np 1
# (launch + MPI_Init + MPI_Finalize), which the plain path never pays.
tiny="$WORK/tiny.pbrt"
sed -e 's/"integer xresolution" [0-9]*/"integer xresolution" 16/' \
    -e 's/"integer yresolution" [0-9]*/"integer yresolution" 16/' "$SCENE" >"$tiny"
# Relative paths in the scene (the volume) resolve from the scene's directory.
sed -i "s|\"string filename\" \"\([^/\"][^\"]*\.vdb\)\"|\"string filename\" \"$(cd "$(dirname "$SCENE")" && pwd)/\1\"|" "$tiny"
REPEAT_SAVE=$REPEAT
REPEAT=5
best_of "$HAZE" render "$tiny" --spp 1 --quiet -o "$WORK/tiny.exr"
t_tiny_plain=$(wall_of)
best_of "$MPIRUN" -np 1 --bind-to none "$HAZE" render "$tiny" --spp 1 --quiet -o "$WORK/tiny.exr"
t_tiny_mpi1=$(wall_of)
c_tiny_mpi1=$(cpu_of)
best_of "$MPIRUN" -np 2 --bind-to none "$HAZE" render "$tiny" --spp 1 --quiet -o "$WORK/tiny.exr"
t_tiny_mpi2=$(wall_of)
c_tiny_mpi2=$(cpu_of)
# What one more rank costs whatever the image: MPI start-up and its own scene build.
c_rank=$(awk -v a="$c_tiny_mpi1" -v b="$c_tiny_mpi2" 'BEGIN { printf "%.2f", b - a }')
REPEAT=$REPEAT_SAVE

rows="$WORK/rows"
: >"$rows"
for mode in split all; do
    for n in 1 2 4; do
        if [ "$mode" = split ]; then
            threads=$((CORES / n)); [ "$threads" -ge 1 ] || threads=1
        else
            threads=$CORES
        fi
        over=
        [ "$n" -gt "$CORES" ] && over=--oversubscribe
        out="$WORK/np$n-$mode.exr"
        best_of "$MPIRUN" -np "$n" $over --bind-to none "$HAZE" render "$SCENE" --spp "$SPP" \
            --seed "$SEED" --threads "$threads" -o "$out"
        t=$(wall_of)
        cpu=$(cpu_of)
        cmp -s "$out" "$ref" && same=yes || same=NO
        wall=$(sed -n 's/.* spp, [0-9]* threads[^,]*, \([0-9.]*\)s, .*/\1/p' "$WORK/best.log")
        claims=$(field 'remote tile claims \([0-9]*\),')
        late=$(field ', \([0-9]*\) late,')
        claim=$(field 'mean wait \([0-9.]*\) us')
        maxw=$(field 'max \([0-9.]*\) ms;')
        svc=$(field 'service thread \([0-9.]*\) CPU s')
        waited=$(field 'waited \([0-9.]*\) s')
        gather=$(field 'gather \([0-9.]*\) s')
        split=$(field 'tiles \([0-9 +]*\) (rank 0')
        echo "$mode $n $threads $t $cpu ${wall:--} ${claim:--} ${maxw:--} ${claims:--} ${late:--} ${svc:--} ${waited:--} ${gather:--} $same ${split:-$tiles}" >>"$rows"
        echo "  $mode: $n ranks x $threads threads: $t s, $cpu CPU s (identical: $same)" >&2
    done
done

load1=$(cut -d' ' -f1-3 /proc/loadavg)
t1_split=$(awk '$1 == "split" && $2 == 1 { print $4 }' "$rows")
t1_all=$(awk '$1 == "all" && $2 == 1 { print $4 }' "$rows")
{
    echo "# MPI scaling: one image across ranks"
    echo
    echo "Generated by \`sh bench/mpi_scaling.sh\` on $(date -u +%Y-%m-%d) ($(uname -m), $CORES cores,"
    echo "$(mpirun --version 2>/dev/null | head -n 1)). Scene \`$SCENE\` at $SPP spp, seed $SEED,"
    echo "$tiles tiles of 16x16; best of $REPEAT runs. All ranks on this one machine"
    echo "(\`--bind-to none\`), so ranks share its $CORES cores: more ranks cannot be faster here;"
    echo "the figures measure what distribution costs. Load average (1, 5, 15 min) at the"
    echo "start: $load0; at the end: $load1 (the machine is shared: wall times move with"
    echo "the other load, CPU seconds much less)."
    echo
    echo "Single process (\`haze render\`, $CORES threads): **${t_single} s** wall, ${c_single} CPU s."
    echo
    echo "| ranks | threads/rank | wall (s, mpirun start to exit) | CPU (s, all processes) | render (s, rank 0 summary) | speedup vs 1 rank | efficiency (speedup / ranks) | tiles per rank | remote tile claims | late claims | tile index wait, mean (us) | max (ms) | service thread CPU (s) | rank 0 waits for others (s) | gather (s) | image = single process |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    while read -r mode n threads t cpu wall claim maxw claims late svc waited gather same split; do
        base=$t1_split; [ "$mode" = all ] && base=$t1_all
        sp=$(awk -v b="$base" -v t="$t" 'BEGIN { printf "%.4f", b / t }')
        eff=$(awk -v s="$sp" -v n="$n" 'BEGIN { printf "%.4f", s / n }')
        printf '| %s | %s | %s | %s | %s | %.2f | %.2f | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' \
            "$n" "$threads" "$t" "$cpu" "$wall" "$sp" "$eff" "$split" "$claims" "$late" "$claim" \
            "$maxw" "$svc" "$waited" "$gather" "$same"
    done <"$rows"
    echo
    echo "Start-up (a 16x16 image at 1 spp, best of 5): plain \`haze render\` ${t_tiny_plain} s;"
    echo "\`mpirun -np 1\` ${t_tiny_mpi1} s; \`mpirun -np 2\` ${t_tiny_mpi2} s. The difference is mpirun's"
    echo "launch plus MPI_Init/MPI_Finalize, which a plain \`haze render\` does not pay (it starts MPI"
    echo "only when OMPI_COMM_WORLD_SIZE or PMIX_RANK says mpirun launched it)."
    echo
    echo "One more rank costs ${c_rank} CPU s whatever the image (MPI start-up, its own parse and"
    echo "scene build, volume load included: CPU of the tiny render under \`mpirun -np 2\` minus"
    echo "\`-np 1\`). Per-tile overhead, from CPU seconds (which do not depend on how the machine"
    echo "is shared): (CPU - 1-rank CPU - (ranks - 1) x ${c_rank}) / tiles:"
    echo
    awk -v tiles="$tiles" -v crank="$c_rank" '
        $2 == 1 { base[$1] = $5; tile[$1] = $5 / tiles * 1000 }
        $2 > 1 {
            printf "- %s, %d ranks x %d threads: %.2f ms per tile", $1, $2, $3, ($5 - base[$1] - ($2 - 1) * crank) / tiles * 1000
            printf " (a tile takes %.1f ms of CPU); a remote claim waited %s us on average.\n", tile[$1], $7
        }' "$rows"
} >"$OUT"
echo "mpi_scaling: wrote $OUT" >&2
