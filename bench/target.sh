#!/bin/sh
# --target-error against a ladder of hand-tuned rungs (bench/README.md): for
# each benchmark scene, two converged renders (the reference, and its noise
# floor: relMSE(ref2, ref) is twice the reference's own error) with jittered
# marching at step 0.5 / shadow step 1 (finer than any step the pilot picks
# here, so the errors below include the rungs' marching bias), rungs of
# jittered at steps 1, 2, 4, without the shadow cache and with it at the step
# and at half the step, at 1, 2, 4, ...
# spp, and --target-error E; each run's time and relMSE; then --target-error
# at E >= 1e-3 with the seeds of BENCH_TARGET_SEEDS (default 2 3).
# Appends "scene mode value seconds relmse spp_mean rung" rows to
# $RESULTS/target.tsv (mode: uniform (value: spp; rung: "estimator step"),
# target (value: E; rung: the steps the pilot chose), pilot (value: E;
# seconds: the step pilot's, from an untimed --stats run), seed (value: E;
# rung: "seed S") or floor).
# Sourced by bench/run.sh (needs lib.sh and its variables).

# target_render E SEED: --target-error E of target_scene's $v into $out;
# sets t (seconds), e (relMSE against $ref) and m (mean samples per pixel).
target_render() {
    t=$(timed "$HAZE" render "$v" --target-error "$1" --threads "$THREADS" --seed "$2" -o "$out" --quiet)
    e=$(errors "$out" "$ref" | cut -d' ' -f2)
    m=$("$HAZE" info "$out" | awk '$1 == "haze:spp_mean" { gsub(/"/, "", $3); print $3 }')
}

# target_scene SCENE NAME REF_SPP "SPPS" "TARGETS" "RUNGS" (RUNGS: "est:step ...")
target_scene() {
    line=$(integrator jittered 0.5)
    ref=$(cached_reference "$1" "$2" tref "target-ref jittered 0.5 $3" "$line" "$3" 999) || exit 1
    ref2=$(cached_reference "$1" "$2" tref2 "target-ref2 jittered 0.5 $3" "$line" "$3" 998) || exit 1
    floor=$(errors "$ref2" "$ref" | awk '{ print $2 / 2 }')
    printf '%s\tfloor\t%s\t0\t%s\t%s\t-\n' "$2" "$3" "$floor" "$3" >>"$RESULTS/target.tsv"
    v=$CACHE/target-$2.pbrt
    out=$CACHE/target-$2.exr
    for r in $6; do
        variant "$v" "$1" "$(integrator "${r%:*}" "${r#*:}")"
        for spp in $4; do
            t=$(timed "$HAZE" render "$v" --spp "$spp" --threads "$THREADS" --seed 1 -o "$out" --quiet)
            e=$(errors "$out" "$ref" | cut -d' ' -f2)
            printf '%s\tuniform\t%s\t%s\t%s\t%s\t%s %s\n' "$2" "$spp" "$t" "$e" "$spp" "${r%:*}" "${r#*:}" >>"$RESULTS/target.tsv"
            echo "  $2 ${r%:*} step ${r#*:} $spp spp: $t s, relmse $e" >&2
        done
    done
    # --target-error from the scene's own settings (jittered, step 1).
    variant "$v" "$1" "$(integrator jittered 1)"
    for te in $5; do
        # The pilot's own time (stat time_pilot_s), in a run of its own:
        # --stats reads clocks in the render loop, so the timed run has none
        # (one sample a pixel: it warns, in its log, that it has no estimate).
        p=$("$HAZE" render "$v" --target-error "$te" --spp 1 --threads "$THREADS" --seed 1 -o "$out" --quiet --stats 2>"$CACHE/pilot-probe.log" |
            awk '$1 == "stat" && $2 == "time_pilot_s" { print $3 }')
        if [ -z "$p" ]; then
            echo "bench: the pilot probe of $2 at E = $te failed:" >&2
            cat "$CACHE/pilot-probe.log" >&2
            exit 1
        fi
        printf '%s\tpilot\t%s\t%s\t-\t-\t-\n' "$2" "$te" "$p" >>"$RESULTS/target.tsv"
        target_render "$te" 1
        st=$("$HAZE" info "$out" | awk '$1 == "haze:stepsize" { $1 = $2 = ""; gsub(/"/, ""); sub(/^ +/, ""); print }')
        printf '%s\ttarget\t%s\t%s\t%s\t%s\t%s\n' "$2" "$te" "$t" "$e" "$m" "${st:--}" >>"$RESULTS/target.tsv"
        echo "  $2 --target-error $te: $t s, relmse $e, $m spp mean, steps ${st:--}" >&2
    done
    # The promise on other seeds (E >= 1e-3: a seed's noise, a firefly, is
    # what misses; docs/performance.md#target-error-lands).
    for seed in ${BENCH_TARGET_SEEDS-2 3}; do
        for te in $5; do
            awk -v e="$te" 'BEGIN { exit !(e >= 1e-3) }' || continue
            target_render "$te" "$seed"
            printf '%s\tseed\t%s\t%s\t%s\t%s\tseed %s\n' "$2" "$te" "$t" "$e" "$m" "$seed" >>"$RESULTS/target.tsv"
            echo "  $2 --target-error $te --seed $seed: $t s, relmse $e, $m spp mean" >&2
        done
    done
}

target_run() {
    printf 'scene\tmode\tvalue\tseconds\trelmse\tspp_mean\trung\n' >"$RESULTS/target.tsv"
    grid="jittered:1 jittered:2 jittered:4 jittered+cache:1 jittered+cache:2 jittered+cache:4"
    grid="$grid jittered+finecache:1 jittered+finecache:2 jittered+finecache:4"
    if [ -n "$BENCH_QUICK" ]; then
        target_scene "$BENCH/scenes/cloud.pbrt" cloud 64 "1 2 4 8" "1e-2 1e-3" "jittered:1 jittered+cache:2"
        target_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 64 "1 4 16" "1e-2" "jittered:1"
    else
        target_scene "$BENCH/scenes/smoke.pbrt" smoke 256 "1 2 4 8 16 32" "1e-2 1e-3 1e-4" "$grid"
        target_scene "$BENCH/scenes/cloud.pbrt" cloud 256 "1 2 4 8 16 32" "1e-2 1e-3 1e-4" "$grid"
        target_scene "$BENCH/scenes/fog-dof.pbrt" fog-dof 1024 "1 2 4 8 16 32 64 128" \
            "1e-2 1e-3 1e-4" "jittered:1"
    fi
}

# The report's section: per scene the rungs, then each target with its
# verdict (relMSE less the reference's floor at most E) and its time against
# the fastest uniform rung at or below E.
report_target() {
    [ -s "$RESULTS/target.tsv" ] || return 0
    echo "## One knob: --target-error"
    echo
    echo "Each scene against a converged render marched at step 0.5 (jittered, 512-1024"
    echo "spp), so the errors include the rungs' marching bias; \`floor\` is the reference's"
    echo "own relMSE (half that of a second reference against it), subtracted before the"
    echo "verdict. Rungs: jittered at steps 1, 2, 4 (shadow step twice), with (\`+cache\`:"
    echo "\`\"float shadowcache\"\` at the step; \`+finecache\`: at half the step) and without"
    echo "the shadow cache, at uniform spp."
    echo "--target-error starts from the scene's settings (jittered, step 1); \`steps\` is"
    echo "what its pilot chose (step, shadow step, cache), \`pilot\` the seconds the pilot"
    echo "took (\`stat time_pilot_s\`, in a run of its own). \`best rung\` is the fastest rung"
    echo "whose relMSE less the floor is at or below E; \`best of 2+ spp\` the fastest such"
    echo "rung of at least two samples, the fewest an estimate of the error needs."
    echo "\`E = ..., seed S\`: the same render with other seeds, whose errors are checked"
    echo "too (not timed against rungs)."
    echo
    for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/target.tsv" | uniq); do
        awk -F'\t' -v s="$scene" '
            $1 != s { next }
            $2 == "floor" { floor = $5; printf "### %s (reference %s spp, floor %.2g)\n\n", s, $3, $5
                print "| run | seconds | relMSE | spp mean | steps | pilot | relMSE - floor <= E | best rung | time / best | best of 2+ spp | time / it |"
                print "|---|---|---|---|---|---|---|---|---|---|---|"; next }
            $2 == "uniform" { n++; us[n] = $7 ", " $3 " spp"; ut[n] = $4; ue[n] = $5; un[n] = $3
                printf "| %s, %s spp | %.3g | %.3g | %s | | | | | | | |\n", $7, $3, $4, $5, $6; next }
            $2 == "pilot" { pilot[$3] = $4; next }
            $2 == "target" {
                best = -1; two = -1
                for (i = 1; i <= n; ++i) if (ue[i] - floor <= $3) {
                    if (best < 0 || ut[i] < ut[best]) best = i
                    if (un[i] >= 2 && (two < 0 || ut[i] < ut[two])) two = i
                }
                ok = ($5 - floor <= $3) ? "yes" : "**no**"
                pl = ($3 in pilot) ? sprintf("%.3g", pilot[$3]) : ""
                printf "| E = %s | %.3g | %.3g | %s | %s | %s | %s ", $3, $4, $5, $6, $7, pl, ok
                if (best > 0) printf "| %s, %.3g s | %.2f ", us[best], ut[best], $4 / ut[best]
                else printf "| none | "
                if (two > 0) printf "| %s, %.3g s | %.2f |\n", us[two], ut[two], $4 / ut[two]
                else printf "| none | |\n"
            }
            $2 == "seed" {
                ok = ($5 - floor <= $3) ? "yes" : "**no**"
                printf "| E = %s, %s | %.3g | %.3g | %s | | | %s | | | | |\n", $3, $7, $4, $5, $6, ok
            }
            END { print "" }' "$RESULTS/target.tsv"
    done
}
