#!/bin/sh
# The bounce axis (bench/README.md): how wrong single scattering is and what
# each bounce of multiple scattering costs. For each scene, a converged
# `volpath` reference (maxdepth 1000, cached), then `singlescatter` (its
# defaults) and `volpath` at maxdepth 1, 2, 4, 8, 16, 64, all at the same spp:
# wall time, RMSE and relMSE against the reference, and the relative error of
# the image mean (the bias a missing bounce leaves; the mean's own noise is far
# below it). Appends "scene integrator maxdepth spp seconds rmse relmse
# mean_rel" rows to $RESULTS/bounce.tsv.
# Sourced by bench/run.sh (needs lib.sh and its variables).

bounce_ref_depth=1000

# mean_rel A.exr REF.exr: (mean A - mean REF) / mean REF over R, G, B.
mean_rel() {
    "$HAZE" diff "$1" "$2" --channels R,G,B | awk '$1 == "all" { print $(NF - 2); found = 1 } END { exit !found }' ||
        { echo "bench: haze diff $1 $2 failed" >&2; exit 1; }
}

# image_mean A.exr: the mean over R, G, B (haze diff of the image with itself).
image_mean() {
    "$HAZE" diff "$1" "$1" --channels R,G,B | awk '$1 == "all" { print $(NF - 4) }'
}

# bounce_reference SCENE NAME SPP: prints the path of the cached reference.
bounce_reference() {
    line="Integrator \"volpath\" \"integer maxdepth\" $bounce_ref_depth"
    key=$(cache_key "$1" -- "bounce-ref $line $3 threads-independent")
    ref=$CACHE/bounce-ref-$2-$key.exr
    if [ ! -f "$ref" ]; then
        v=$CACHE/bounce-ref-$2.pbrt
        variant "$v" "$1" "$line"
        echo "  reference $2: volpath maxdepth $bounce_ref_depth, $3 spp (cached as $(basename "$ref"))" >&2
        t=$(timed "$HAZE" render "$v" --spp "$3" --threads "$THREADS" --seed 4321 -o "$ref.tmp.exr" --quiet)
        mv "$ref.tmp.exr" "$ref"
        echo "  reference $2 took $t s" >&2
    fi
    echo "$ref"
}

# bounce_scene SCENE NAME REF_SPP SPP "DEPTHS"
bounce_scene() {
    ref=$(bounce_reference "$1" "$2" "$3") || exit 1
    m=$(image_mean "$ref")
    # The scene does the work it claims: a lit reference.
    awk -v m="$m" 'BEGIN { exit !(m > 1e-3) }' || { echo "bench: $2: reference is black (mean $m)" >&2; exit 1; }
    for rung in singlescatter $5; do
        v=$CACHE/bounce-$2.pbrt
        if [ "$rung" = singlescatter ]; then
            variant "$v" "$1" 'Integrator "singlescatter"'
            integ=singlescatter depth=-
        else
            variant "$v" "$1" "Integrator \"volpath\" \"integer maxdepth\" $rung"
            integ=volpath depth=$rung
        fi
        out=$CACHE/bounce-$2.exr
        t=$(timed "$HAZE" render "$v" --spp "$4" --threads "$THREADS" --seed 1 -o "$out" --quiet)
        e=$(errors "$out" "$ref")
        b=$(mean_rel "$out" "$ref")
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$2" "$integ" "$depth" "$4" "$t" "$(echo "$e" | cut -d' ' -f1)" "$(echo "$e" | cut -d' ' -f2)" "$b" >>"$RESULTS/bounce.tsv"
        echo "  $2 $integ $depth spp $4: $t s, rmse relmse $e, mean $b" >&2
    done
    printf '%s\treference\t%s\t%s\t-\t-\t-\t%s\n' "$2" "$bounce_ref_depth" "$3" "$m" >>"$RESULTS/bounce.tsv"
}

bounce_run() {
    printf 'scene\tintegrator\tmaxdepth\tspp\tseconds\trmse\trelmse\tmean_rel\n' >"$RESULTS/bounce.tsv"
    if [ -n "$BENCH_QUICK" ]; then
        bounce_scene "$BENCH/scenes/cloud.pbrt" cloud 16 4 "1 4 64"
        bounce_scene "$BENCH/scenes/fog-room.pbrt" fog-room 32 4 "1 4 64"
    else
        bounce_scene "$BENCH/scenes/cloud.pbrt" cloud 512 16 "1 2 4 8 16 64"
        bounce_scene "$BENCH/scenes/fog-room.pbrt" fog-room 1024 16 "1 2 4 8 16 64"
    fi
}
