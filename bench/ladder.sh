#!/bin/sh
# The speed/accuracy ladder (bench/README.md): for each benchmark scene, a
# converged unbiased reference (cached), then estimator x step size x spp,
# each rung's wall time and its error against the reference.
# Appends "scene estimator step spp seconds rmse relmse" rows to $RESULTS/ladder.tsv.
# Sourced by bench/run.sh (needs lib.sh and its variables).

ladder_ref_est=ratio
has_estimator residual && ladder_ref_est=residual

# ladder_reference SCENE NAME SPP: prints the path of the cached reference.
ladder_reference() {
    cached_reference "$1" "$2" ref "ladder-ref $ladder_ref_est $3 threads-independent" \
        "$(integrator "$ladder_ref_est" 1)" "$3" 12345
}

# ladder_scene SCENE NAME REF_SPP "ESTIMATORS" "STEPS" "SPPS"
ladder_scene() {
    ref=$(ladder_reference "$1" "$2" "$3") || exit 1
    for est in $4; do
        steps=$5
        [ "$est" = exact ] && steps=1
        for step in $steps; do
            v=$CACHE/rung-$2.pbrt
            if [ "$est" = exact ]; then
                variant "$v" "$1" "$(integrator jittered 1)"
            else
                variant "$v" "$1" "$(integrator "$est" "$step")"
            fi
            for spp in $6; do
                out=$CACHE/rung-$2.exr
                t=$(timed "$HAZE" render "$v" --spp "$spp" --threads "$THREADS" --seed 1 -o "$out" --quiet)
                e=$(errors "$out" "$ref")
                printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$2" "$est" "$step" "$spp" "$t" "$(echo "$e" | tr ' ' '\t')" >>"$RESULTS/ladder.tsv"
                echo "  $2 $est step $step spp $spp: $t s, rmse relmse $e" >&2
            done
        done
    done
}

ladder_run() {
    ests="raymarch jittered ratio"
    has_estimator residual && ests="$ests residual"
    printf 'scene\testimator\tstep\tspp\tseconds\trmse\trelmse\n' >"$RESULTS/ladder.tsv"
    if [ -n "$BENCH_QUICK" ]; then
        ladder_scene "$BENCH/scenes/smoke.pbrt" smoke 16 "$ests" "1 2" "1 4"
        ladder_scene "$BENCH/scenes/cloud.pbrt" cloud 16 "$ests" "1 2" "1 4"
        ladder_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 64 exact 1 "1 4"
    else
        ladder_scene "$BENCH/scenes/smoke.pbrt" smoke 128 "$ests" "1 2 4" "1 4 16"
        ladder_scene "$BENCH/scenes/cloud.pbrt" cloud 128 "$ests" "1 2 4" "1 4 16"
        ladder_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 256 exact 1 "1 4 16 64"
    fi
}
