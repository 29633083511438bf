#!/bin/sh
# The peer (bench/README.md): OpenVDB's vdb_render and haze on the same
# volumes/smoke.vdb, camera and light (bench/scenes/peer-thin.pbrt and
# peer-thick.pbrt hold haze's side of the mapping), each against its own
# converged image. Writes $RESULTS/peer.tsv (one row per render:
# config renderer mode step spp seconds rmse relmse) and
# $RESULTS/peer-match.tsv (haze's converged pixel-centre image against
# vdb_render's converged image). Sourced by bench/run.sh.

# vdb_render's view of bench/scenes/peer-*.pbrt (the fov is horizontal there).
PEER_VIEW="-res 640x480 -translate 0.15,1.05,-3.7 -lookat -0.05,0.98,-0.03 -up 0,1,0 -fov 44.356"
PEER_LIGHT="-light 0.3,3,0.2,1,1,1 -gain 0 -cutoff 1e-5 -name density"

# peer_coefficients CONFIG: vdb_render's -absorb/-scatter (per voxel length).
peer_coefficients() {
    case $1 in
    thick) echo "-absorb 0.1,0.1,0.1 -scatter 1.5,1.5,1.5" ;;  # vdb_render's defaults
    thin) echo "-absorb 0.005,0.005,0.005 -scatter 0.075,0.075,0.075" ;;  # defaults / 20
    esac
}

# vdb CONFIG STEP SHADOWSTEP OUT.exr: one vdb_render image.
vdb() {
    # shellcheck disable=SC2086
    vdb_render "$BENCH/../volumes/smoke.vdb" "$4" $PEER_VIEW $PEER_LIGHT $(peer_coefficients "$1") \
        -step "$2" -shadowstep "$3" -cpus "$THREADS"
}

# vdb_ref_path CONFIG STEP WORDS: the cache file of a vdb_render reference
# at STEP (WORDS: its shadow step, and how it was made), keyed by the volume,
# vdb_render's version and its arguments, not by haze's.
vdb_ref_path() {
    echo "$CACHE/vdb-ref-$1-$(content_key "$BENCH/../volumes/smoke.vdb" -- "vdb $(vdb_render -version 2>&1) $PEER_VIEW $PEER_LIGHT $(peer_coefficients "$1") $2 $3").exr"
}

peer_config() {
    cfg=$1
    # vdb_render's converged image. Its error is first order in the shadow
    # step (its default shadow step, 3, leaves the thick image 19% too
    # bright), and a rung at the reference's own shadow step would share its
    # bias: two renders at step 0.05 and shadow steps 0.25 and 0.125 voxels
    # are extrapolated to shadow step 0 (bench/exr_extrapolate.c: 2 FINE -
    # COARSE), against which every rung measures its own error. Step 0.01
    # with shadow steps fine enough would take most of an hour.
    vref_step=0.05 vref_sstep=0.125
    [ -n "$BENCH_QUICK" ] && vref_step=0.1 vref_sstep=0.25
    vref=$(vdb_ref_path "$cfg" "$vref_step" "$vref_sstep extrapolated")
    if [ ! -f "$vref" ]; then
        coarse_sstep=$(awk -v s="$vref_sstep" 'BEGIN { print 2 * s }')
        for ss in "$vref_sstep" "$coarse_sstep"; do
            out=$(vdb_ref_path "$cfg" "$vref_step" "$ss")
            [ -f "$out" ] && continue
            echo "  vdb_render reference $cfg: step $vref_step, shadow step $ss" >&2
            t=$(timed vdb "$cfg" "$vref_step" "$ss" "$CACHE/vdb-tmp.exr")
            mv "$CACHE/vdb-tmp.exr" "$out"
            echo "  vdb_render reference $cfg took $t s" >&2
        done
        "$EXR_EXTRAPOLATE" "$(vdb_ref_path "$cfg" "$vref_step" "$vref_sstep")" \
            "$(vdb_ref_path "$cfg" "$vref_step" "$coarse_sstep")" "$vref" ||
            { echo "bench: $EXR_EXTRAPOLATE failed" >&2; exit 1; }
    fi
    # The ladder: vdb_render's best step / shadow-step pairs (issue 20): each
    # step with shadow steps of half, one and two steps, and down to 0.0625
    # voxels for the finest errors (step 0.25 gains nothing over 0.5 there:
    # 2x the time for the same error, as the shadow step dominates). Its time
    # goes to the shadow rays (steps x shadow steps lookups), so at coarse
    # errors a coarse step with a finer shadow step is its fastest (the
    # "S/SS" rungs in trade.md).
    # Steps 8 and 6 too, with shadow steps of one, a half and a quarter step:
    # the coarse end sampled as finely as haze's raymarch ladder samples it
    # (steps 8, 6, 5, 4 and 3).
    pairs="8/8 8/4 8/2 6/6 6/3 6/1.5 4/8 4/4 4/2 2/4 2/2 2/1 1/2 1/1 1/0.5 1/0.25 0.5/1 0.5/0.5 0.5/0.25 0.5/0.125 0.5/0.0625"
    [ -n "$BENCH_QUICK" ] && pairs="2/4 2/2 1/2"
    for p in $pairs; do
        s=${p%/*} ss=${p#*/}
        t=$(timed vdb "$cfg" "$s" "$ss" "$CACHE/vdb-rung.exr")
        e=$(errors "$CACHE/vdb-rung.exr" "$vref")
        printf '%s\tvdb_render\tcentre\t%s\t1\t%s\t%s\t%s\n' "$cfg" "$p" "$t" "$(echo "$e" | tr ' ' '\t')" "${e#* }" >>"$RESULTS/peer.tsv"
        echo "  peer $cfg vdb_render step $s shadow step $ss: $t s, rmse relmse $e" >&2
    done

    scene=$BENCH/scenes/peer-$cfg.pbrt
    modes=aa
    if has_option disable-pixel-jitter; then modes="centre aa"; else
        echo "  (haze has no --disable-pixel-jitter: pixel-centre comparison skipped)" >&2
    fi
    ref_spp=256
    [ -n "$BENCH_QUICK" ] && ref_spp=16
    for mode in $modes; do
        flag=
        [ "$mode" = centre ] && flag=--disable-pixel-jitter
        if [ "$mode" = centre ]; then
            # At pixel centres haze's raymarch (midpoint steps, distant light)
            # is deterministic, like vdb_render: its converged image is a fine
            # raymarch at 1 spp, with no noise; its error is estimated from
            # the same render at twice the steps (midpoint: error ~ step^2, so
            # MSE(2h vs h) ~ 9 MSE(h)).
            rstep=0.0625
            [ -n "$BENCH_QUICK" ] && rstep=0.25
            rsteps=$(awk -v s="$rstep" 'BEGIN { print s, 2 * s, 2 * s, 4 * s }')
            set -- $rsteps
            key=$(cache_key "$scene" -- "peer-ref raymarch $1 $2 centre")
            href=$CACHE/haze-ref-$cfg-$mode-$key.exr
            key2=$(cache_key "$scene" -- "peer-ref raymarch $3 $4 centre")
            href2=$CACHE/haze-ref2-$cfg-$mode-$key2.exr
            for r in "$href $1 $2" "$href2 $3 $4"; do
                set -- $r
                [ -f "$1" ] && continue
                variant "$CACHE/peer-ref.pbrt" "$scene" "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" \"float stepsize\" $2 \"float shadowstepsize\" $3"
                echo "  haze reference $cfg centre: raymarch $2 / $3, 1 spp" >&2
                t=$(timed "$HAZE" render "$CACHE/peer-ref.pbrt" $flag --spp 1 --threads "$THREADS" --seed 12345 -o "$CACHE/peer-tmp.exr" --quiet)
                mv "$CACHE/peer-tmp.exr" "$1"
                echo "  haze reference took $t s" >&2
            done
            floor=$(errors "$href2" "$href" | awk '{ printf "%.6g %.6g", $1 * $1 / 9, $2 / 9 }')
        else
            key=$(cache_key "$scene" -- "peer-ref $ladder_ref_est $ref_spp $mode")
            href=$CACHE/haze-ref-$cfg-$mode-$key.exr
            if [ ! -f "$href" ]; then
                variant "$CACHE/peer-ref.pbrt" "$scene" "$(integrator "$ladder_ref_est" 1)"
                echo "  haze reference $cfg $mode: $ladder_ref_est, $ref_spp spp" >&2
                # shellcheck disable=SC2086
                t=$(timed "$HAZE" render "$CACHE/peer-ref.pbrt" $flag --spp "$ref_spp" --threads "$THREADS" --seed 12345 -o "$CACHE/peer-tmp.exr" --quiet)
                mv "$CACHE/peer-tmp.exr" "$href"
                echo "  haze reference $cfg $mode took $t s" >&2
            fi
            # The reference's own noise (its floor): a second, independent
            # reference at a quarter of the samples, B, against it, A:
            # E[MSE(B, A)] = var A + var B = 5 var A.
            key2=$(cache_key "$scene" -- "peer-ref-floor $ladder_ref_est $ref_spp $mode")
            href2=$CACHE/haze-ref2-$cfg-$mode-$key2.exr
            if [ ! -f "$href2" ]; then
                variant "$CACHE/peer-ref.pbrt" "$scene" "$(integrator "$ladder_ref_est" 1)"
                # shellcheck disable=SC2086
                "$HAZE" render "$CACHE/peer-ref.pbrt" $flag --spp $((ref_spp / 4)) --threads "$THREADS" --seed 54321 -o "$CACHE/peer-tmp.exr" --quiet
                mv "$CACHE/peer-tmp.exr" "$href2"
            fi
            floor=$(errors "$href2" "$href" | awk '{ printf "%.6g %.6g", $1 * $1 / 5, $2 / 5 }')
        fi
        printf '%s\t%s\t%s\n' "$cfg" "$mode" "$(echo "$floor" | tr ' ' '\t')" >>"$RESULTS/peer-floor.tsv"
        floor_rel=${floor#* }
        echo "  haze reference $cfg $mode: error floor (MSE relMSE) $floor" >&2
        if [ "$mode" = centre ] || [ "$modes" = aa ]; then
            # How close the two models come (bench/README.md: the mapping).
            e=$(errors "$href" "$vref")
            m=$("$HAZE" diff "$href" "$vref" --channels R,G,B | awk '$1 == "all" { print $9, $10, $11 }')
            printf '%s\t%s\t%s\t%s\n' "$cfg" "$mode" "$(echo "$e" | tr ' ' '\t')" "$(echo "$m" | tr ' ' '\t')" >>"$RESULTS/peer-match.tsv"
            echo "  peer $cfg: haze ($mode) vs vdb_render converged: rmse relmse $e; mean haze, vdb, rel diff $m" >&2
        fi
        # rung ESTIMATOR STEP SPP: one haze render against the reference.
        rung() {
            variant "$CACHE/peer-rung.pbrt" "$scene" "$(integrator "$1" "$2")"
            # shellcheck disable=SC2086
            t=$(timed "$HAZE" render "$CACHE/peer-rung.pbrt" $flag --spp "$3" --threads "$THREADS" --seed 1 -o "$CACHE/peer-rung.exr" --quiet)
            e=$(errors "$CACHE/peer-rung.exr" "$href")
            # relMSE net of the reference's error; "<X" (X a tenth of the
            # measured value) when the measured value is within 10% of
            # that error: unresolved, X is an upper bound.
            net=$(echo "$e" | awk -v f="$floor_rel" '{ n = $2 - f; if (n < 0.1 * $2) printf "<%.6g", 0.1 * $2; else printf "%.6g", n }')
            printf '%s\thaze\t%s\t%s %s\t%s\t%s\t%s\t%s\n' "$cfg" "$mode" "$1" "$2" "$3" "$t" "$(echo "$e" | tr ' ' '\t')" "$net" >>"$RESULTS/peer.tsv"
            echo "  peer $cfg haze $mode $1 step $2 spp $3: $t s, rmse relmse $e" >&2
        }
        hsteps="1 2 4"
        hspps="1 2 4 8 16"
        [ -n "$BENCH_QUICK" ] && hsteps=2 && hspps="1 4"
        for s in $hsteps; do
            for spp in $hspps; do
                rung jittered "$s" "$spp"
                rung jittered+cache "$s" "$spp"
                rung jittered+finecache "$s" "$spp"
            done
        done
        # Deterministic at pixel centres: one sample is the converged pixel.
        if [ "$mode" = centre ]; then
            rsteps="8 6 5 4 3 2 1 0.5"
            [ -n "$BENCH_QUICK" ] && rsteps="4 2"
            for s in $rsteps; do
                rung raymarch "$s" 1
                rung raymarch+cache "$s" 1
                rung raymarch+finecache "$s" 1
            done
            [ -z "$BENCH_QUICK" ] && rung raymarch+cache 0.25 1
        fi
    done
}

peer_run() {
    printf 'config\trenderer\tmode\tstep\tspp\tseconds\trmse\trelmse\trelmse_net\n' >"$RESULTS/peer.tsv"
    printf 'config\tmode\tmse_floor\trelmse_floor\n' >"$RESULTS/peer-floor.tsv"
    printf 'config\thaze_mode\trmse\trelmse\tmean_haze\tmean_vdb\trel_diff\n' >"$RESULTS/peer-match.tsv"
    if ! command -v vdb_render >/dev/null; then
        echo "bench: vdb_render missing (Debian libopenvdb-tools): peer skipped" >&2
        return 0
    fi
    peer_config thin
    peer_config thick
}
