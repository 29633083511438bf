#!/bin/sh
# --target-error against the uniform spp ladder (bench/README.md): for each
# benchmark scene with its default integrator (jittered, step 1), two converged
# renders of that integrator with different seeds (the reference, and its noise
# floor: relMSE(ref2, ref) is twice the reference's own error), uniform rungs
# of 1, 2, 4, ... spp and --target-error E; each run's time and relMSE.
# Appends "scene mode value seconds relmse spp_mean" rows to $RESULTS/target.tsv
# (mode: uniform (value: spp), target (value: E) or floor).
# Sourced by bench/run.sh (needs lib.sh and its variables).

# target_scene SCENE NAME REF_SPP "SPPS" "TARGETS"
target_scene() {
    line=$(integrator jittered 1)
    ref=$(cached_reference "$1" "$2" tref "target-ref jittered $3" "$line" "$3" 999) || exit 1
    ref2=$(cached_reference "$1" "$2" tref2 "target-ref2 jittered $3" "$line" "$3" 998) || exit 1
    floor=$(errors "$ref2" "$ref" | awk '{ print $2 / 2 }')
    printf '%s\tfloor\t%s\t0\t%s\t%s\n' "$2" "$3" "$floor" "$3" >>"$RESULTS/target.tsv"
    v=$CACHE/target-$2.pbrt
    variant "$v" "$1" "$line"
    out=$CACHE/target-$2.exr
    for spp in $4; do
        t=$(timed "$HAZE" render "$v" --spp "$spp" --threads "$THREADS" --seed 1 -o "$out" --quiet)
        e=$(errors "$out" "$ref" | cut -d' ' -f2)
        printf '%s\tuniform\t%s\t%s\t%s\t%s\n' "$2" "$spp" "$t" "$e" "$spp" >>"$RESULTS/target.tsv"
        echo "  $2 uniform $spp spp: $t s, relmse $e" >&2
    done
    for te in $5; do
        t=$(timed "$HAZE" render "$v" --target-error "$te" --threads "$THREADS" --seed 1 -o "$out" --quiet)
        e=$(errors "$out" "$ref" | cut -d' ' -f2)
        m=$("$HAZE" info "$out" | awk '$1 == "haze:spp_mean" { gsub(/"/, "", $3); print $3 }')
        printf '%s\ttarget\t%s\t%s\t%s\t%s\n' "$2" "$te" "$t" "$e" "$m" >>"$RESULTS/target.tsv"
        echo "  $2 --target-error $te: $t s, relmse $e, $m spp mean" >&2
    done
}

target_run() {
    printf 'scene\tmode\tvalue\tseconds\trelmse\tspp_mean\n' >"$RESULTS/target.tsv"
    if [ -n "$BENCH_QUICK" ]; then
        target_scene "$BENCH/scenes/cloud.pbrt" cloud 64 "1 2 4 8" "1e-2 1e-3"
        target_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 64 "1 4 16" "1e-2"
    else
        target_scene "$BENCH/scenes/smoke.pbrt" smoke 512 "1 2 4 8 16 32" "1e-2 1e-3 1e-4"
        target_scene "$BENCH/scenes/cloud.pbrt" cloud 512 "1 2 4 8 16 32" "1e-2 1e-3 1e-4"
        target_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 1024 "1 2 4 8 16 32 64 128" \
            "1e-2 1e-3 1e-4"
    fi
}

# The report's section: per scene the rungs, then each target with its
# verdict (relMSE less the reference's floor at most E) and its time against
# the fastest uniform rung at or below E.
report_target() {
    [ -s "$RESULTS/target.tsv" ] || return 0
    echo "## One knob: --target-error"
    echo
    echo "Each scene with its default integrator (jittered, step 1) against the converged"
    echo "render of that integrator; \`floor\` is the reference's own relMSE (half that of a"
    echo "second reference against it), subtracted before the verdict. \`best rung\` is the"
    echo "fastest uniform spp whose relMSE is at or below E."
    echo
    for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/target.tsv" | uniq); do
        awk -F'\t' -v s="$scene" '
            $1 != s { next }
            $2 == "floor" { floor = $5; printf "### %s (reference %s spp, floor %.2g)\n\n", s, $3, $5
                print "| run | seconds | relMSE | spp mean | relMSE - floor <= E | best rung | time / best |"
                print "|---|---|---|---|---|---|---|"; next }
            $2 == "uniform" { n++; us[n] = $3; ut[n] = $4; ue[n] = $5
                printf "| %s spp | %.3g | %.3g | %s | | | |\n", $3, $4, $5, $6; next }
            $2 == "target" {
                best = -1
                for (i = 1; i <= n; ++i) if (ue[i] - floor <= $3 && (best < 0 || ut[i] < ut[best])) best = i
                ok = ($5 - floor <= $3) ? "yes" : "**no**"
                if (best > 0)
                    printf "| E = %s | %.3g | %.3g | %s | %s | %s spp, %.3g s | %.2f |\n", $3, $4, $5, $6, ok, us[best], ut[best], $4 / ut[best]
                else
                    printf "| E = %s | %.3g | %.3g | %s | %s | none | |\n", $3, $4, $5, $6, ok
            }
            END { print "" }' "$RESULTS/target.tsv"
    done
}
