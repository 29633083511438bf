#!/bin/sh
# Turns the raw tables of a bench run ($RESULTS/*.tsv) into
# $RESULTS/trade.md and, with gnuplot, $RESULTS/trade.png.
# Sourced by bench/run.sh.

# The Pareto front of "seconds error" rows on stdin (sorted by time; a row is
# kept when its error is below every faster row's).
front() { sort -g -k1,1 -k2,2 | awk 'NR == 1 || $2 < 0.95 * best { print; best = $2 }'; }

# time_to TARGETS...: for the front on stdin, the time to reach each target
# error by log-log interpolation between the front points around it; "<=T"
# when even the fastest rung is below the target, "-" when none reaches it.
time_to() {
    awk -v targets="$*" '
        { t[NR] = $1; e[NR] = $2 }
        END {
            n = split(targets, T, " ")
            for (k = 1; k <= n; ++k) {
                E = T[k]; out = "-"
                for (i = 1; i <= NR; ++i) {
                    if (e[i] > E) continue
                    if (i == 1) { out = sprintf("<=%.3g", t[1]); break }
                    lt = log(t[i - 1]) + (log(E) - log(e[i - 1])) * (log(t[i]) - log(t[i - 1])) / (log(e[i]) - log(e[i - 1]))
                    out = sprintf("%.3g", exp(lt)); break
                }
                printf "%s%s", out, k < n ? " " : "\n"
            }
        }'
}

report_ladder() {
    [ -s "$RESULTS/ladder.tsv" ] || return 0
    echo "## The ladder"
    echo
    echo "Error against each scene's converged reference ($ladder_ref_est tracking, cached"
    echo "in bench/cache/), over R, G, B. Time is the process wall clock (start-up,"
    echo "scene loading and EXR writing included; the median of three runs when one"
    echo "takes under 2 s, of seven under 0.5 s), $THREADS threads. Shadow step = 2 x step. \`*\` marks the"
    echo "scene's Pareto front (no faster rung has a relMSE within 5% of it)."
    echo
    for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/ladder.tsv" | uniq); do
        echo "### $scene"
        echo
        echo "| estimator | step (voxels) | spp | time (s) | RMSE | relMSE | |"
        echo "|---|---|---|---|---|---|---|"
        awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s { print $5, $7 }' "$RESULTS/ladder.tsv" | front >"$CACHE/front.txt"
        awk -F'\t' -v s="$scene" 'FNR == NR { f[$0] = 1; next }
            FNR > 1 && $1 == s { printf "| %s | %s | %s | %s | %.4g | %.4g | %s |\n", $2, $2 == "exact" ? "-" : $3, $4, $5, $6, $7, (($5 " " $7) in f) ? "*" : "" }' \
            "$CACHE/front.txt" "$RESULTS/ladder.tsv"
        echo
        echo "Recommended ($scene): the front, fastest first:"
        awk -F'\t' -v s="$scene" 'FNR == NR { f[$0] = 1; next }
            FNR > 1 && $1 == s && (($5 " " $7) in f) { printf "%s\t%s step %s, %s spp (%.3g s, relMSE %.3g)\n", $5, $2, $2 == "exact" ? "-" : $3, $4, $5, $7 }' \
            "$CACHE/front.txt" "$RESULTS/ladder.tsv" | sort -g | cut -f2 | awk '{ printf "%s%s", (NR > 1 ? "; " : ""), $0 } END { print "." }'

        echo
    done
}

PEER_TARGETS="0.1 0.03 0.01 0.003 0.001 0.0003 0.0001 3e-05 1e-05 3e-06"

report_peer() {
    [ -s "$RESULTS/peer.tsv" ] && [ "$(wc -l <"$RESULTS/peer.tsv")" -gt 1 ] || return 0
    echo "## The peer: vdb_render"
    echo
    echo "How close the models come: haze's converged image against vdb_render's"
    echo "converged image (step 0.05, shadow step 0.5) of the same configuration (bench/README.md has"
    echo "the mapping and where they differ):"
    echo
    echo "| config | haze image | RMSE | relMSE | mean haze | mean vdb_render | rel. diff of means |"
    echo "|---|---|---|---|---|---|---|"
    awk -F'\t' 'NR > 1 { printf "| %s | %s | %.4g | %.4g | %.4g | %.4g | %+.2f%% |\n", $1, $2, $3, $4, $5, $6, 100 * $7 }' "$RESULTS/peer-match.tsv"
    echo
    echo "Renders (each against its own converged image; vdb_render renders one ray"
    echo "per pixel centre, its rungs \`S/SS\` at step S and shadow step SS voxels, against"
    echo "its image extrapolated to shadow step 0 (bench/README.md);"
    echo "haze \`centre\` with --disable-pixel-jitter, \`aa\` anti-aliased;"
    echo "haze \`raymarch S\` and \`jittered S\` rungs, step S, shadow step 2S; \`+cache\`:"
    echo "the same with \`\"float shadowcache\" S\`, docs/media.md; \`+finecache\`: with"
    echo "\`\"float shadowcache\" S/2\`):"
    echo
    echo "haze's references: at pixel centres a deterministic raymarch (step 0.0625),"
    echo "whose error is estimated from the same render at twice the steps (MSE/9);"
    echo "anti-aliased, 256 spp of tracking, whose Monte Carlo noise is measured with a"
    echo "second, independent reference at a quarter of the samples (B against A:"
    echo "E[MSE] = var A + var B = 5 var A):"
    echo
    echo "| config | haze image | reference error MSE | reference error relMSE |"
    echo "|---|---|---|---|"
    awk -F'\t' 'NR > 1 { printf "| %s | %s | %.3g | %.3g |\n", $1, $2, $3, $4 }' "$RESULTS/peer-floor.tsv"
    echo
    echo "\"net\" is the measured relMSE minus that noise (the error against the"
    echo "true converged image, in expectation); \"<X\" when the measured value is"
    echo "within 10% of the noise (unresolved): X, a tenth of the measured value, is"
    echo "an upper bound, and the time-to-error below uses it (which can only favour"
    echo "vdb_render). vdb_render is deterministic: its net is its measured relMSE."
    echo
    echo "| config | renderer | mode | step | spp | time (s) | RMSE | relMSE | relMSE net |"
    echo "|---|---|---|---|---|---|---|---|---|"
    awk -F'\t' 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %.4g | %.4g | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9 ~ /^</ ? sprintf("<%.3g", substr($9, 2)) : sprintf("%.4g", $9) }' "$RESULTS/peer.tsv"
    echo
    echo "Time to reach a net relMSE (log-log interpolation on each one's Pareto front;"
    echo "\`<=T\`: already below it at the fastest rung; \`-\`: not reached on the"
    echo "ladder). Target: haze (pixel centre) at most 1/3 of vdb_render's time."
    echo
    echo "| config | relMSE | vdb_render (s) | haze centre (s) | haze aa (s) | centre / vdb_render | target <= 0.333 |"
    echo "|---|---|---|---|---|---|---|"
    for cfg in thin thick; do
        v=$(awk -F'\t' -v c="$cfg" 'NR > 1 && $1 == c && $2 == "vdb_render" { v = $9; sub(/^</, "", v); print $6, v }' "$RESULTS/peer.tsv" | front | time_to $PEER_TARGETS)
        hc=$(awk -F'\t' -v c="$cfg" 'NR > 1 && $1 == c && $2 == "haze" && $3 == "centre" { v = $9; sub(/^</, "", v); print $6, v }' "$RESULTS/peer.tsv" | front | time_to $PEER_TARGETS)
        ha=$(awk -F'\t' -v c="$cfg" 'NR > 1 && $1 == c && $2 == "haze" && $3 == "aa" { v = $9; sub(/^</, "", v); print $6, v }' "$RESULTS/peer.tsv" | front | time_to $PEER_TARGETS)
        [ -n "$v" ] || continue
        echo "$PEER_TARGETS|$v|${hc:-}|${ha:-}" | awk -F'|' -v c="$cfg" '{
            n = split($1, T, " "); split($2, V, " "); split($3, C, " "); split($4, A, " ")
            for (k = 1; k <= n; ++k) {
                if (C[k] == "") C[k] = "n/a"
                if (A[k] == "") A[k] = "n/a"
                r = "-"; ok = "-"
                if (V[k] ~ /^[0-9]/ && C[k] ~ /^[0-9]/) { r = sprintf("%.2f", C[k] / V[k]); ok = C[k] / V[k] <= 1 / 3 ? "met" : "missed" }
                else if (V[k] ~ /^[0-9]/ && C[k] ~ /^<=/) { x = substr(C[k], 3); r = sprintf("<=%.2f", x / V[k]); ok = x / V[k] <= 1 / 3 ? "met" : "undecided" }
                else if (V[k] ~ /^<=/ && C[k] ~ /^[0-9]/) { ok = "undecided" }
                if (V[k] == "-" && C[k] == "-") continue
                printf "| %s | %s | %s | %s | %s | %s | %s |\n", c, T[k], V[k], C[k], A[k], r, ok
            }
        }'
    done
    echo
}

report_bounce() {
    [ -s "$RESULTS/bounce.tsv" ] || return 0
    echo "## The bounce axis"
    echo
    echo "Against each scene's converged \`volpath\` reference (maxdepth 1000), every rung at the"
    echo "same spp, 2 threads, seed 1. *mean* is the relative error of the image mean over R, G, B:"
    echo "the light a missing bounce leaves out (the mean's noise is far below it); relMSE adds"
    echo "each rung's own noise. *time* is the process wall clock (median of three under 2 s, of seven under 0.5 s)."
    echo
    for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/bounce.tsv" | uniq); do
        awk -F'\t' -v s="$scene" '$1 == s && $2 == "reference" { printf "### %s (reference: %s spp, image mean %s)\n", s, $4, $8 }' "$RESULTS/bounce.tsv"
        echo
        echo "| integrator | maxdepth | spp | time (s) | time / singlescatter | RMSE | relMSE | mean |"
        echo "|---|---|---|---|---|---|---|---|"
        awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s && $2 != "reference" {
            if ($2 == "singlescatter") t0 = $5
            printf "| %s | %s | %s | %s | %.2f | %s | %s | %+.1f%% |\n", $2, $3, $4, $5, (t0 > 0 ? $5 / t0 : 0), $6, $7, 100 * $8 }' "$RESULTS/bounce.tsv"
        echo
        # Against pbrt-v4 (PBRT set): for unbiased estimators relMSE x time is
        # constant, so their ratio is haze's time over pbrt-v4's at equal error.
        awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s && $2 == "volpath" && $3 == 64 { h = $5 * $7 }
            NR > 1 && $1 == s && $2 == "pbrt-v4" { p = $5 * $7 }
            END { if (h > 0 && p > 0) printf "haze volpath (maxdepth 64) needs %.2fx pbrt-v4'"'"'s time for the same error (relMSE x time ratio; target <= 1, aim 0.5).\n\n", h / p }' "$RESULTS/bounce.tsv"
    done
}

report_yardsticks() {
    [ -s "$RESULTS/yardsticks.tsv" ] || return 0
    echo "## Yardsticks"
    echo
    echo "| measure | value | target | verdict | how |"
    echo "|---|---|---|---|---|"
    awk -F'\t' 'NR > 1 { printf "| %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5 }' "$RESULTS/yardsticks.tsv"
    echo
}

report_plot() {
    command -v gnuplot >/dev/null || { echo "bench: no gnuplot: trade.png not drawn" >&2; return 0; }
    d=$CACHE/plot; rm -rf "$d"; mkdir -p "$d"
    # One file per scene and estimator: that estimator's front.
    touch "$RESULTS/ladder.tsv" "$RESULTS/peer.tsv"
    for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/ladder.tsv" | uniq); do
        for est in $(awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s { print $2 }' "$RESULTS/ladder.tsv" | sort -u); do
            awk -F'\t' -v s="$scene" -v e="$est" 'NR > 1 && $1 == s && $2 == e { print $5, $7 }' "$RESULTS/ladder.tsv" | front >"$d/$scene.$est.front"
            awk -F'\t' -v s="$scene" -v e="$est" 'NR > 1 && $1 == s && $2 == e { print $5, $7 }' "$RESULTS/ladder.tsv" >"$d/$scene.$est.all"
        done
    done
    for cfg in thin thick; do
        for who in "vdb_render centre" "haze centre" "haze aa"; do
            set -- $who
            awk -F'\t' -v c="$cfg" -v r="$1" -v m="$2" 'NR > 1 && $1 == c && $2 == r && $3 == m { v = $9; sub(/^</, "", v); print $6, v }' "$RESULTS/peer.tsv" | front >"$d/peer-$cfg.$1-$2.front"
        done
    done
    {
        echo 'set terminal pngcairo noenhanced size 1400,1000 font ",10"'
        echo "set output '$RESULTS/trade.png'"
        echo 'set logscale xy; set grid; set key top right; set format y "%.0e"'
        echo 'set xlabel "wall time (s)"; set ylabel "relMSE vs converged"'
        echo 'set multiplot layout 2,3 title "haze: error vs time (Pareto front per estimator; points: every rung)"'
        for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/ladder.tsv" | uniq); do
            echo "set title '$scene'"
            printf 'plot'
            sep=' '
            for f in "$d/$scene".*.front; do
                est=$(basename "$f" .front); est=${est#"$scene".}
                printf "%s'%s' using 1:2 with linespoints lw 2 title '%s', '%s' using 1:2 with points pt 6 notitle" "$sep" "$f" "$est" "$d/$scene.$est.all"
                sep=', '
            done
            echo
        done
        for cfg in thin thick; do
            if [ -s "$d/peer-$cfg.vdb_render-centre.front" ]; then
                echo "set title 'peer, $cfg: net relMSE vs own converged image'"
                printf 'plot'
                sep=' '
                for who in vdb_render-centre haze-centre haze-aa; do
                    [ -s "$d/peer-$cfg.$who.front" ] || continue
                    printf "%s'%s' using 1:2 with linespoints lw 2 title '%s'" "$sep" "$d/peer-$cfg.$who.front" "$who"
                    sep=', '
                done
                echo
            fi
        done
        if [ -s "$RESULTS/bounce.tsv" ]; then
            echo "set title 'bounce axis: volpath maxdepth 1..64 (labels), singlescatter (x)'"
            printf 'plot'
            sep=' '
            for scene in $(awk -F'\t' 'NR > 1 { print $1 }' "$RESULTS/bounce.tsv" | uniq); do
                awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s && $2 == "volpath" { print $5, $7, $3 }' "$RESULTS/bounce.tsv" >"$d/bounce-$scene.vp"
                awk -F'\t' -v s="$scene" 'NR > 1 && $1 == s && $2 == "singlescatter" { print $5, $7 }' "$RESULTS/bounce.tsv" >"$d/bounce-$scene.ss"
                printf "%s'%s' using 1:2 with linespoints lw 2 title '%s volpath', '%s' using 1:2:3 with labels offset 1,0.7 notitle, '%s' using 1:2 with points pt 2 ps 2 title '%s singlescatter'" \
                    "$sep" "$d/bounce-$scene.vp" "$scene" "$d/bounce-$scene.vp" "$d/bounce-$scene.ss" "$scene"
                sep=', '
            done
            echo
        fi
        echo 'unset multiplot'
    } >"$d/trade.gp"
    gnuplot "$d/trade.gp" || echo "bench: gnuplot failed (see $d/trade.gp)" >&2
}

report_run() {
    {
        echo "# Speed against accuracy: make bench results"
        echo
        echo "Written by \`make bench\`$([ -n "$BENCH_QUICK" ] && echo " (BENCH_QUICK=1: the short smoke run, not the full ladder)") on $(date -u '+%Y-%m-%d %H:%M UTC'),"
        echo "$(nproc) CPUs ($(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo)), load average before the run $BENCH_LOAD,"
        [ "$PARTS" = "ladder peer bounce target yardsticks scale" ] || echo "parts run this time: ${PARTS:-none} (the other tables are from the previous run),"
        echo "$(haze_id) (version and src/ tree). The plot is [trade.png](trade.png); bench/README.md says what"
        echo "each part measures."
        echo
        report_ladder
        report_peer
        report_bounce
        report_target
        report_yardsticks
    } >"$RESULTS/trade.md"
    report_plot
}
