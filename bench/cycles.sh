#!/bin/sh
# The cycles part (bench/results/cycles.md): haze's multiple scattering
# (`Integrator "volpath"`) against Blender's Cycles at equal error on
# bench/scenes/cloud.pbrt, which bench/cycles/scene.py rebuilds for Cycles.
# For haze in each configuration of CYCLES_HAZE and for Cycles at each volume
# step rate of CYCLES_RATES:
#   - a converged reference of its own (CYCLES_REF_SPP, seed 4321, cached);
#   - rungs at CYCLES_RUNGS spp (seed 1), each a whole process under GNU time
#     (CPU seconds = user + sys, 2 threads), and relMSE against its own
#     reference (haze diff, R G B);
#   - the error of one sample e1 = relMSE(n) / (1/n + 1/REF) at the top rung
#     (errors fall as 1/spp; the reference's own noise taken out), the time
#     model t(n) = t0 + ts n (least squares through the rungs: t0 is start-up
#     and loading), and so the CPU time to reach relMSE E: t0 + ts e1 / E.
# Each own-reference error hides a renderer's bias, so the references are
# also compared with each other: per-channel means and relMSE against haze's.
# Writes $RESULTS/cycles.tsv and $RESULTS/cycles.md. Skipped without blender.
# Sourced by bench/run.sh (needs lib.sh and its variables).

CYCLES_DEPTH=64                          # haze volpath maxdepth; Cycles bounces to match
CYCLES_RATES=${BENCH_CYCLES_RATES:-1 2 4 8}  # Cycles' volume_step_rate (1: its default)
# haze's configurations: "haze" (pbrt-v4's estimator, unbiased) and haze
# with knobs, named by them: cacheS is "float shadowcache" S, stepS is
# "float stepsize" S (both biased), splitK is "integer mediumsplits" K
# (unbiased: it shares the reference of the configuration without it), e.g.
# haze-cache1-step2-split4.
CYCLES_HAZE=${BENCH_CYCLES_HAZE:-haze haze-split4 haze-cache1 haze-step4 haze-step4-split4 haze-cache1-step1-split4 haze-cache1-step2-split4}
CYCLES_REF_SPP=${BENCH_CYCLES_REF_SPP:-2048}
CYCLES_RUNGS=${BENCH_CYCLES_RUNGS:-16 64 256}
CYCLES_ERRORS="1e-2 1e-3 1e-4"           # 1e-4 is extrapolated (beyond the top rung)
CYCLES_TOP=$(cd "$BENCH/.." && pwd)

# cycles_cmd RATE OUT SPP SEED: the Blender command line of one render.
cycles_cmd() {
    echo blender -b --factory-startup -noaudio -t "$THREADS" -P "$BENCH/cycles/scene.py" -- \
        --vdb "$CYCLES_TOP/volumes/plume.vdb" --out "$2" --spp "$3" --seed "$4" \
        --threads "$THREADS" --step-rate "$1" --maxdepth "$CYCLES_DEPTH"
}

# cycles_knobs WHO: the Integrator parameters of haze configuration WHO.
cycles_knobs() {
    for ck in $(echo "$1" | tr '-' ' '); do
        case $ck in
        haze) ;;
        cache*) printf ' "float shadowcache" %s' "${ck#cache}" ;;
        step*) printf ' "float stepsize" %s' "${ck#step}" ;;
        split*) printf ' "integer mediumsplits" %s' "${ck#split}" ;;
        *) echo "bench: cycles: unknown haze configuration $1" >&2; exit 1 ;;
        esac
    done
}

# cycles_unsplit WHO: configuration WHO without its splitK (the same
# expectation: its reference).
cycles_unsplit() { echo "$1" | sed 's/-split[0-9]*//g'; }

# cycles_scene WHO: haze configuration WHO's scene (made by cycles_run).
cycles_scene() { echo "$CACHE/cycles-$1.pbrt"; }

# cycles_render WHO OUT SPP SEED [TIMEFILE]: one render by haze (WHO = haze or
# a configuration of it) or by Cycles at step rate R (WHO = cycles-R); timed
# into TIMEFILE when given. The command is split on spaces: paths without
# spaces.
cycles_render() {
    case $1 in
    haze*) cr_cmd="$HAZE render $(cycles_scene "$1") --spp $3 --threads $THREADS --seed $4 -o $2 --quiet" ;;
    cycles-*) cr_cmd=$(cycles_cmd "${1#cycles-}" "$2" "$3" "$4") ;;
    esac
    if [ -n "${5:-}" ]; then
        # shellcheck disable=SC2086 # the command's words
        cpu_timed "$5" 1e30 $cr_cmd
    else
        # shellcheck disable=SC2086
        $cr_cmd >>"$LOG" 2>&1 || { echo "bench: failed: $cr_cmd" >&2; tail -5 "$LOG" >&2; exit 1; }
    fi
}

# cycles_reference WHO: the path of WHO's cached reference. haze's key: the
# scene and the binary's own hash (not haze_id's src/ tree: the binary timed
# may be a copy built from another tree; BENCH_HAZE_ID overrides it, as in
# lib.sh); Cycles': the scene, scene.py, the grid and Blender's version.
cycles_reference() {
    cref_words="cycles-ref $1 maxdepth $CYCLES_DEPTH spp $CYCLES_REF_SPP seed 4321"
    case $1 in
    haze*) cref_words="$cref_words$(cycles_knobs "$1")"
        cref_key=$(key_of "${BENCH_HAZE_ID:-$("$HAZE" --version 2>&1) $(sha256sum <"$HAZE" | cut -c1-40)}" \
        "$BENCH/scenes/cloud.pbrt" -- "$cref_words") ;;
    *) cref_key=$(content_key "$BENCH/scenes/cloud.pbrt" "$BENCH/cycles/scene.py" "$CYCLES_TOP/volumes/plume.vdb" -- \
        "$cref_words $(blender --version 2>/dev/null | head -1)") ;;
    esac
    cref=$CACHE/cycles/ref-$1-$cref_key.exr
    if [ ! -f "$cref" ]; then
        echo "  reference $1: $CYCLES_REF_SPP spp (cached as $(basename "$cref"))" >&2
        cycles_render "$1" "$cref.tmp.exr" "$CYCLES_REF_SPP" 4321
        mv "$cref.tmp.exr" "$cref"
    fi
    echo "$cref"
}

# cycles_means A.exr: "R G B" means.
cycles_means() {
    "$HAZE" diff "$1" "$1" --channels R,G,B | awk '$1 ~ /^[RGB]$/ { printf "%s%s", s, $(NF - 4); s = " " } END { print "" }'
}

cycles_run() {
    command -v blender >/dev/null 2>&1 || { echo "bench: cycles: blender is not on PATH, part skipped" >&2; return 0; }
    [ -x /usr/bin/time ] || { echo "bench: the cycles part needs GNU time (/usr/bin/time)" >&2; exit 1; }
    mkdir -p "$CACHE/cycles"
    # haze's scene: the variant sits in $CACHE (two levels under the
    # repository, as the scene) so the scene's relative grid path resolves.
    case " $CYCLES_HAZE " in
    " haze "*) ;;
    *) echo "bench: cycles: BENCH_CYCLES_HAZE must start with haze (the unbiased reference)" >&2; exit 1 ;;
    esac
    # Each configuration's scene, and its unsplit twin's.
    for who in $(for w in $CYCLES_HAZE; do echo "$w"; cycles_unsplit "$w"; done | sort -u); do
        cycles_knobs "$who" >/dev/null # exits on an unknown name
        variant "$(cycles_scene "$who")" "$BENCH/scenes/cloud.pbrt" \
            "Integrator \"volpath\" \"integer maxdepth\" $CYCLES_DEPTH$(cycles_knobs "$who")"
    done
    tsv=$RESULTS/cycles.tsv
    # rung rows: relMSE against the renderer's own reference; reference rows:
    # relMSE against haze's reference, and the image's means.
    printf 'who\tkind\tspp\tcpu_s\twall_s\trelmse\tmean_r\tmean_g\tmean_b\n' >"$tsv"
    href=$(cycles_reference haze) || exit 1
    # A splitK configuration's unsplit twin is measured too, before it: the
    # fit takes the twin's reference noise out of its error.
    timed=$(for w in $CYCLES_HAZE; do cycles_unsplit "$w"; echo "$w"; done | awk '!seen[$0]++')
    for who in $timed $(for r in $CYCLES_RATES; do echo "cycles-$r"; done); do
        wref=$href
        [ "$(cycles_unsplit "$who")" = haze ] || wref=$(cycles_reference "$(cycles_unsplit "$who")") || exit 1
        # The reference against haze's: the means and the relMSE (the bias
        # of the model and of the step, plus both references' noise).
        printf '%s\treference\t%s\t-\t-\t%s\t%s\n' "$who" "$CYCLES_REF_SPP" "$(errors "$wref" "$href" | cut -d' ' -f2)" \
            "$(cycles_means "$wref" | tr ' ' '\t')" >>"$tsv"
        for n in $CYCLES_RUNGS; do
            out=$CACHE/cycles/$who-$n.exr
            cycles_render "$who" "$out" "$n" 1 "$out.cpu"
            e=$(errors "$out" "$wref" | cut -d' ' -f2)
            printf '%s\trung\t%s\t%s\t%s\t%s\n' "$who" "$n" "$(cut -d' ' -f1 "$out.cpu")" "$(cut -d' ' -f2 "$out.cpu")" "$e" >>"$tsv"
            echo "  $who $n spp: cpu wall $(cat "$out.cpu") s, relmse $e" >&2
        done
    done
    cycles_report "$tsv" >"$RESULTS/cycles.md"
    echo "bench: cycles: $RESULTS/cycles.md" >&2
}

# cycles_report TSV: the markdown report from the rows.
cycles_report() {
    awk -F '\t' -v refspp="$CYCLES_REF_SPP" -v errs="$CYCLES_ERRORS" -v rates="$CYCLES_RATES" \
        -v date="$(date -u '+%Y-%m-%d %H:%M UTC')" -v load="$BENCH_LOAD" -v threads="$THREADS" \
        -v haze="$HAZE" -v env="$(env | grep '^BENCH_CYCLES_' | tr '\n' ' ')" \
        -v hv="$("$HAZE" --version 2>&1 | head -1)" -v bv="$(blender --version 2>/dev/null | head -1)" '
    NR == 1 { next }
    $2 == "reference" { rmse[$1] = $6; mr[$1] = $7; mg[$1] = $8; mb[$1] = $9; next }
    $2 == "rung" {
        w = $1; k = ++nr[w]; sp[w, k] = $3; cpu[w, k] = $4; err[w, k] = $6
        if (!(w in seen)) { seen[w] = 1; order[++nw] = w }
    }
    function fit(w,   k, n, sx, sy, sxx, sxy) {
        n = nr[w]; sx = sy = sxx = sxy = 0
        for (k = 1; k <= n; k++) { sx += sp[w, k]; sy += cpu[w, k]; sxx += sp[w, k] ^ 2; sxy += sp[w, k] * cpu[w, k] }
        ts[w] = (n * sxy - sx * sy) / (n * sxx - sx * sx); t0[w] = (sy - ts[w] * sx) / n
        # The top rung'"'"'s error holds the reference'"'"'s noise, e1 / REF of the
        # configuration that rendered it: a splitK configuration'"'"'s is its
        # unsplit twin'"'"'s (timed too, and fitted first).
        uw[w] = w; sub(/-split[0-9]+/, "", uw[w])
        if (uw[w] != w && (uw[w] in e1))
            e1[w] = (err[w, n] - e1[uw[w]] / refspp) * sp[w, n]
        else
            e1[w] = err[w, n] / (1 / sp[w, n] + 1 / refspp)
        # the slope of log relMSE against log spp, first rung to top (-1: pure noise)
        slope[w] = log(err[w, n] / err[w, 1]) / log(sp[w, n] / sp[w, 1])
    }
    function tE(w, E) { return t0[w] + ts[w] * e1[w] / E }
    function rel(a, b) { return a / b - 1 < 0 ? 1 - a / b : a / b - 1 }
    function ok(w) { return rel(mr[w], mr["haze"]) <= 0.01 && rel(mg[w], mg["haze"]) <= 0.01 && rel(mb[w], mb["haze"]) <= 0.01 }
    END {
        for (i = 1; i <= nw; i++) if (order[i] !~ /-split[0-9]/) fit(order[i])
        for (i = 1; i <= nw; i++) if (order[i] ~ /-split[0-9]/) fit(order[i])
        # The best step rate: least CPU time at relMSE 1e-3 among the rates
        # whose reference keeps every channel mean within 1% of haze'"'"'s (a
        # coarser step is faster and darker: an error against its own
        # reference does not see that).
        best = ""; split(rates, rl, " ")
        for (i in rl) {
            w = "cycles-" rl[i]
            if (!(w in seen) || !ok(w)) continue
            if (best == "" || tE(w, 1e-3) < tE(best, 1e-3)) best = w
        }
        print "# haze volpath against Cycles at equal error"
        print ""
        printf "%s, 2 threads (`--threads %s`, `blender -t %s`), load average before: %s. haze: %s; %s.\n", date, threads, threads, load, hv, bv
        print ""
        printf "    %sBENCH_PARTS=cycles sh bench/run.sh %s\n", env, haze
        print ""
        print "The scene: `bench/scenes/cloud.pbrt` (`volumes/plume.vdb`, sigma_a 0.5 and sigma_s 60 per unit density, g 0.6,"
        print "a distant light and a uniform sky, 320x240, gaussian filter), haze under `Integrator \"volpath\" \"integer maxdepth\" 64`."
        print "Cycles renders `bench/cycles/scene.py`'"'"'s rebuild of it (its comments say how each part is matched):"
        print ""
        print "- axes: pbrt (x, y, z) -> Blender (x, z, y), a mirror that turns the left-handed y-up scene into the right-handed"
        print "  z-up one without mirroring the image; the camera by the same LookAt, fov 40 on the vertical (shorter) axis;"
        print "- the grid: full precision (default half), the object moved by -1/2 voxel (Cycles samples voxel centres half a voxel"
        print "  off OpenVDB'"'"'s convention; the shift beats 0 and +1/2 voxel on relMSE against haze), Volume Scatter (colour 1,"
        print "  density 60 x grid, anisotropy 0.6) + Volume Absorption (colour 0, density 0.5 x grid);"
        print "- lights: a sun of strength 9 W/m^2, colour (1, 8.5/9, 8/9), angle 0 (default 0.53 deg); the world background"
        print "  (0.08, 0.1, 0.14), strength 1;"
        print "- paths: volume bounces 63 (pbrt'"'"'s depth 64 counts the scattering vertices, Cycles'"'"' bounces 0 is single scattering;"
        print "  default 0), max and transparent bounces 64 (default 8), no clamping (default indirect 10), volume max steps 100000;"
        print "- film: gaussian width 2 (Cycles'"'"' gaussian of width w has sigma w/4: sigma 0.5 px as pbrt'"'"'s; default Blackman-Harris"
        print "  1.5), Standard view, linear 32-bit EXR, no denoising, no adaptive sampling; the rest Cycles'"'"' defaults (its sampler,"
        print "  light threshold 0.01, volume clipping 0.001, automatic step: one voxel times the scene'"'"'s step rate)."
        print ""
        print "## CPU seconds to reach relMSE E, each against its own converged reference"
        print ""
        printf "t(E) = t0 + ts e1 / E from rungs at"
        for (k = 1; k <= nr["haze"]; k++) printf " %d", sp["haze", k]
        printf " spp (1e-4: extrapolated beyond the top rung); references %d spp. CPU = user + sys of the whole process (start-up included: t0).\n\n", refspp
        printf "| E | haze | Cycles rate 1 (default) | haze / Cycles | Cycles rate %s (best: the fastest at 1e-3 whose means stay within 1%% of haze'"'"'s) | haze / Cycles |\n", substr(best, 8)
        print "|---|---|---|---|---|---|"
        n = split(errs, el, " ")
        for (i = 1; i <= n; i++) {
            E = el[i]; h = tE("haze", E); c1 = tE("cycles-1", E); cb = tE(best, E)
            printf "| %s | %.1f | %.1f | %.2f | %.1f | %.2f |\n", E, h, c1, h / c1, cb, h / cb
        }
        print ""
        print "## haze'"'"'s knobs"
        print ""
        print "haze-cacheS: `volpath` with `\"float shadowcache\" S` (distant lights'"'"' transmittance read from the shadow cache at S voxels);"
        print "haze-stepS: `\"float stepsize\" S` (flights and shadow rays marched at S voxels instead of tracked, Cycles'"'"' estimator);"
        print "haze-splitK: `\"integer mediumsplits\" K` (K continuations from each path'"'"'s first scattering point in the cloud; unbiased)."
        print "Each against its own reference (splitK: the one without it), as Cycles'"'"' rates; the bias column is its reference'"'"'s"
        print "mean over haze'"'"'s unbiased one (channel average; Cycles'"'"' rows for comparison)."
        print ""
        printf "| renderer | bias | t(1e-2) | / Cycles rate %s | t(1e-3) | / Cycles | t(1e-4) | / Cycles |\n", substr(best, 8)
        print "|---|---|---|---|---|---|---|---|"
        for (i = 1; i <= nw; i++) {
            w = order[i]
            b = ((mr[w] / mr["haze"] + mg[w] / mg["haze"] + mb[w] / mb["haze"]) / 3 - 1) * 100
            printf "| %s | %+.2f%% | %.1f | %.2f | %.1f | %.2f | %.1f | %.2f |\n", w, b,
                tE(w, 1e-2), tE(w, 1e-2) / tE(best, 1e-2), tE(w, 1e-3), tE(w, 1e-3) / tE(best, 1e-3),
                tE(w, 1e-4), tE(w, 1e-4) / tE(best, 1e-4)
        }
        print ""
        print "## The fits"
        print ""
        print "| renderer | rungs: spp, CPU s, relMSE | t0 s | ts s/spp | e1 (relMSE of 1 spp) | slope | t(1e-2) | t(1e-3) | t(1e-4) |"
        print "|---|---|---|---|---|---|---|---|---|"
        for (i = 1; i <= nw; i++) {
            w = order[i]; s = ""
            for (k = 1; k <= nr[w]; k++) s = s sprintf("%s%d: %.2f, %.3g", k > 1 ? "; " : "", sp[w, k], cpu[w, k], err[w, k])
            printf "| %s | %s | %.2f | %.4f | %.3g | %.2f | %.1f | %.1f | %.1f |\n", w, s, t0[w], ts[w], e1[w], slope[w], tE(w, 1e-2), tE(w, 1e-3), tE(w, 1e-4)
        }
        print ""
        print "## The converged references"
        print ""
        print "Means over the image and relMSE against haze'"'"'s reference (which holds both references'"'"' noise, about e1/REF each, and the bias between them)."
        print ""
        print "The net relMSE takes both references'"'"' noise out (e1 / REF each): what is left is the bias between"
        print "the two renderers (the model, the step), which an error against a renderer'"'"'s own reference does not see."
        print ""
        print "| reference | mean R | mean G | mean B | R, G, B vs haze | relMSE vs haze | net of noise |"
        print "|---|---|---|---|---|---|---|"
        for (i = 1; i <= nw; i++) {
            w = order[i]
            net = (uw[w] == "haze") ? 0 : rmse[w] - ((uw[w] in e1 ? e1[uw[w]] : e1[w]) + e1["haze"]) / refspp
            printf "| %s | %.5f | %.5f | %.5f | %+.2f%%, %+.2f%%, %+.2f%% | %.3g | %.2g |\n", w, mr[w], mg[w], mb[w],
                100 * (mr[w] / mr["haze"] - 1), 100 * (mg[w] / mg["haze"] - 1), 100 * (mb[w] / mb["haze"] - 1), rmse[w], net
        }
    }' "$1"
}
