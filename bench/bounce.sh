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
    cached_reference "$1" "$2" bounce-ref "bounce-ref $line $3 threads-independent" "$line" "$3" 4321
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

# bounce_peer SCENE NAME REF_SPP SPP: with PBRT set (a pbrt-v4 binary; bench/README.md
# says how to build one), pbrt-v4 renders the scene with volpath maxdepth 64 at
# SPP, beside haze's row of the same settings: time and error against haze's
# reference. Grid files are converted to .nvdb for it (nanovdb_convert).
bounce_peer() {
    [ -n "${PBRT:-}" ] || return 0
    ref=$(bounce_reference "$1" "$2" "$3") || exit 1
    d=$CACHE/bounce-peer-$2; mkdir -p "$d"
    # Relative paths resolve against the scene's directory; .vdb grids become .nvdb.
    sdir=$(cd "$(dirname "$1")" && pwd)
    awk -v sdir="$sdir" -v d="$d" '{
        while (match($0, /"[^"]*\.vdb"/)) {
            f = substr($0, RSTART + 1, RLENGTH - 2)
            src = (f ~ /^\//) ? f : sdir "/" f
            n = split(f, parts, "/"); out = d "/" parts[n]; sub(/\.vdb$/, ".nvdb", out)
            print src " " out > (d "/convert.txt")
            $0 = substr($0, 1, RSTART - 1) "\"" out "\"" substr($0, RSTART + RLENGTH)
        }
        print
    }' "$1" >"$d/scene.pbrt"
    if [ -f "$d/convert.txt" ]; then
        while read -r src out; do
            [ -f "$out" ] || nanovdb_convert -f "$src" "$out" >>"$LOG" 2>&1 ||
                { echo "bench: nanovdb_convert $src failed" >&2; exit 1; }
        done <"$d/convert.txt"
    fi
    # pbrt resolves relative paths against the including file: the variant sits beside the copy.
    printf 'Integrator "volpath" "integer maxdepth" 64\nInclude "%s"\n' "$d/scene.pbrt" >"$d/vp.pbrt"
    out=$d/pbrt.exr
    t=$(timed "$PBRT" --nthreads "$THREADS" --spp "$4" --seed 1 --outfile "$out" --quiet "$d/vp.pbrt")
    e=$(errors "$out" "$ref")
    b=$(mean_rel "$out" "$ref")
    printf '%s\tpbrt-v4\t64\t%s\t%s\t%s\t%s\t%s\n' "$2" "$4" "$t" "$(echo "$e" | cut -d' ' -f1)" "$(echo "$e" | cut -d' ' -f2)" "$b" >>"$RESULTS/bounce.tsv"
    echo "  $2 pbrt-v4 volpath 64 spp $4: $t s, rmse relmse $e, mean $b" >&2
}

bounce_run() {
    printf 'scene\tintegrator\tmaxdepth\tspp\tseconds\trmse\trelmse\tmean_rel\n' >"$RESULTS/bounce.tsv"
    if [ -n "$BENCH_QUICK" ]; then
        ref_cloud=16 ref_room=32 spp=4 depths="1 4 64"
    else
        ref_cloud=512 ref_room=1024 spp=16 depths="1 2 4 8 16 64"
    fi
    bounce_scene "$BENCH/scenes/cloud.pbrt" cloud "$ref_cloud" "$spp" "$depths"
    bounce_peer "$BENCH/scenes/cloud.pbrt" cloud "$ref_cloud" "$spp"
    bounce_scene "$BENCH/scenes/fog-room.pbrt" fog-room "$ref_room" "$spp" "$depths"
    bounce_peer "$BENCH/scenes/fog-room.pbrt" fog-room "$ref_room" "$spp"
}
