#!/bin/sh
# The scale part (bench/README.md, issue 43): what a grid's resolution costs.
# The unit sphere of density 1 - r at R = 25 .. 400 voxels across its radius
# (the same optical depth at every R) and a sparse grid (small balls, 2% of a
# 1000^3 bound), generated into $CACHE/scale by haze_scale_volumes. For each:
# loading (the file read once, `haze info`, a one-pixel render of the .nvdb,
# and of the .vdb converting and from the conversion cache), then the
# default integrator at --target-error E, and volpath maxdepth 1 and pbrt-v4
# (PBRT=) at the error the default reached, each against a converged volpath
# reference. Every run is a whole process under GNU time (wall seconds and
# peak RSS; wall seconds to the millisecond from the clock around it) and under `timeout` (BENCH_SCALE_TIMEOUT). Writes
# $RESULTS/scale.tsv and $RESULTS/scale.md.
# Sourced by bench/run.sh (needs lib.sh and its variables).

SCALE_DIR=$CACHE/scale
SCALE_TIMEOUT=${BENCH_SCALE_TIMEOUT:-300}
SCALE_ERRORS=${BENCH_SCALE_ERRORS:-1e-2 1e-3}
SCALE_GEN=${HAZE_SCALE_VOLUMES:-$(dirname "$HAZE")/bench/haze_scale_volumes}
# The unbiased renders at equal error: a pilot of this many samples gives
# the error of one sample, e1 (relMSE falls as 1/spp).
scale_pilot_spp=16

# scale_run_one OUT CMD...: runs CMD under GNU time and timeout; writes
# "seconds peak_kib status" to OUT (status: ok, timeout, or failed). The
# seconds are the wall clock around the run to the millisecond (GNU time's
# own %e has 10 ms steps, as large as a 300 MB file's read), spawning GNU
# time and timeout included (a few ms, as for every run timed here). Short
# runs vary most with the machine's load: the median of 7 runs under 0.5 s,
# of 3 under 2 s.
scale_run_one() {
    o=$1
    shift
    # (sh has no locals: names the callers do not use)
    ts= kb=0 st=ok sro_n=0
    while :; do
        rc=0
        sro_t0=$(now)
        /usr/bin/time -f '%e %M' -o "$o.time" timeout "$SCALE_TIMEOUT" "$@" >"$o.out" 2>&1 || rc=$?
        sro_t1=$(now)
        cat "$o.out" >>"$LOG"
        [ $rc -eq 124 ] && st=timeout
        [ $rc -ne 0 ] && [ $rc -ne 124 ] && st=failed
        # GNU time writes "Command exited with non-zero status" first.
        t=$(elapsed "$sro_t0" "$sro_t1") k=$(tail -1 "$o.time" | cut -d' ' -f2)
        ts="$ts $t" sro_n=$((sro_n + 1))
        [ "$k" -gt "$kb" ] && kb=$k
        [ "$st" = ok ] || break
        awk -v t="$t" -v n="$sro_n" 'BEGIN { exit !((t < 0.5 && n < 7) || (t < 2 && n < 3)) }' || break
    done
    [ "$st" = failed ] && { echo "bench: failed: $*" >&2; tail -3 "$o.out" >&2; }
    printf '%s %s %s\n' "$(printf '%s\n' $ts | median)" "$kb" "$st" >"$o"
}

# scale_field FILE N: field N of scale_run_one's result.
scale_field() { cut -d' ' -f"$2" "$1"; }

# scale_volume NAME: generates $SCALE_DIR/NAME.vdb and .nvdb when missing.
scale_volume() {
    [ -f "$SCALE_DIR/$1.nvdb" ] && [ -f "$SCALE_DIR/$1.vdb" ] && return 0
    [ -x "$SCALE_GEN" ] || { echo "bench: $SCALE_GEN is not built (cmake --build build)" >&2; exit 1; }
    case $1 in
    sphere-*) set -- sphere "${1#sphere-}" ;;
    esac
    echo "  generating $*" >&2
    "$SCALE_GEN" "$SCALE_DIR" "$@" >>"$LOG" 2>&1 || { echo "bench: haze_scale_volumes $* failed" >&2; exit 1; }
}

# scale_scene OUT.pbrt NAME FILE INTEGRATOR-LINE: the scene of volume NAME
# (a sphere or the sparse balls) reading FILE, lit by a distant light and a
# dim sky, 160x120.
scale_scene() {
    {
        echo "$4"
        case $2 in
        sparse)
            echo 'LookAt 0.5 1.2 -4.2   0 0 0   0 1 0'
            echo 'Camera "perspective" "float fov" 40' ;;
        *)
            echo 'LookAt 0 0.4 -3.6   0 0 0   0 1 0'
            echo 'Camera "perspective" "float fov" 40' ;;
        esac
        echo 'Film "rgb" "integer xresolution" 160 "integer yresolution" 120 "string filename" "scale.exr"'
        echo 'Sampler "zsobol" "integer pixelsamples" 1'
        echo 'WorldBegin'
        echo 'LightSource "distant" "point3 from" [1.5 2 -1] "point3 to" [0 0 0] "rgb L" [8 8 8]'
        echo 'LightSource "infinite" "rgb L" [0.05 0.07 0.1]'
        case $2 in
        sparse)
            # Balls of 10 voxels (0.02): sigma_t 100 is 2 along a ball's diameter.
            echo "MakeNamedMedium \"vol\" \"string type\" \"nanovdb\" \"string filename\" \"$3\""
            echo '    "rgb sigma_a" [10 10 10] "rgb sigma_s" [90 90 90] "float g" 0.3'
            echo 'AttributeBegin'
            echo '  Material "interface"'
            echo '  MediumInterface "vol" ""'
            echo '  Shape "trianglemesh" "integer indices" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5  0 5 4  2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]'
            echo '      "point3 P" [-1.01 -1.01 -1.01  1.01 -1.01 -1.01  -1.01 1.01 -1.01  1.01 1.01 -1.01  -1.01 -1.01 1.01  1.01 -1.01 1.01  -1.01 1.01 1.01  1.01 1.01 1.01]'
            echo 'AttributeEnd' ;;
        *)
            # Optical depth 5 along a diameter at every R.
            echo "MakeNamedMedium \"vol\" \"string type\" \"nanovdb\" \"string filename\" \"$3\""
            echo '    "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [4.5 4.5 4.5] "float g" 0.3'
            echo 'AttributeBegin'
            echo '  Material "interface"'
            echo '  MediumInterface "vol" ""'
            echo '  Shape "sphere" "float radius" 1.05'
            echo 'AttributeEnd' ;;
        esac
    } >"$1"
}

# scale_net RELMSE: RELMSE less the reference's own error ($scale_floor).
scale_net() { awk -v e="$1" -v f="$scale_floor" 'BEGIN { printf "%.3g", e - f }'; }

# scale_row VOLUME RUN E RESULT-FILE RELMSE SPP NOTE: one row of scale.tsv.
scale_row() {
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$(scale_field "$4" 1)" \
        "$(scale_field "$4" 2)" "$(scale_field "$4" 3)" "$5" "$6" "$7" >>"$RESULTS/scale.tsv"
    echo "  $1 $2 E=$3: $(cat "$4") relmse $5 spp $6 $7" >&2
}

# scale_loading NAME: the file read once, haze info, one-pixel renders.
scale_loading() {
    nv=$SCALE_DIR/$1.nvdb
    d=$SCALE_DIR/run; mkdir -p "$d"
    mb=$(awk -v b="$(stat -c %s "$nv")" 'BEGIN { printf "%.1f", b / 1048576 }')
    vmb=$(awk -v b="$(stat -c %s "$SCALE_DIR/$1.vdb")" 'BEGIN { printf "%.1f", b / 1048576 }')
    # warm: the read is timed from the page cache, as the loads that follow
    # are (a 1.1 GiB file evicted by the runs before took 2.3 s, one run)
    cat "$nv" >/dev/null
    scale_run_one "$d/r" sh -c "cat '$nv' >/dev/null"
    scale_row "$1" "cat .nvdb" - "$d/r" - - "$mb MiB"
    scale_run_one "$d/r" "$HAZE" info "$nv"
    scale_row "$1" "haze info .nvdb" - "$d/r" - - "$mb MiB"
    scale_scene "$d/load.pbrt" "$1" "$nv" ""
    scale_run_one "$d/r" "$HAZE" render "$d/load.pbrt" --spp 1 --pixelbounds 0,1,0,1 --threads "$THREADS" -o "$d/load.exr" --quiet
    scale_row "$1" "load .nvdb" - "$d/r" - - "one-pixel render"
    cp "$d/r" "$d/load-$1"
    scale_scene "$d/load-vdb.pbrt" "$1" "$SCALE_DIR/$1.vdb" ""
    scale_run_one "$d/r" env HAZE_CACHE_DIR= "$HAZE" render "$d/load-vdb.pbrt" --spp 1 --pixelbounds 0,1,0,1 --threads "$THREADS" -o "$d/load.exr" --quiet
    scale_row "$1" "load .vdb converting" - "$d/r" - - "$vmb MiB, the reader process included"
    rm -rf "$SCALE_DIR/vdb-cache"
    HAZE_CACHE_DIR="$SCALE_DIR/vdb-cache" "$HAZE" render "$d/load-vdb.pbrt" --spp 1 --pixelbounds 0,1,0,1 --threads "$THREADS" -o "$d/load.exr" --quiet >>"$LOG" 2>&1
    scale_run_one "$d/r" env HAZE_CACHE_DIR="$SCALE_DIR/vdb-cache" "$HAZE" render "$d/load-vdb.pbrt" --spp 1 --pixelbounds 0,1,0,1 --threads "$THREADS" -o "$d/load.exr" --quiet
    scale_row "$1" "load .vdb cached" - "$d/r" - - "from the conversion cache"
    rm -rf "$SCALE_DIR/vdb-cache"
}

# scale_reference NAME SPP: the cached volpath maxdepth 1 reference; proves
# the scene does work (density lookups, a lit sphere).
scale_reference() {
    v=$SCALE_DIR/ref-$1.pbrt
    line='Integrator "volpath" "integer maxdepth" 1'
    scale_scene "$v" "$1" "$SCALE_DIR/$1.nvdb" "$line"
    # Keyed by the scene and the volume, not haze's version: volpath is
    # unbiased, and the six references take about 20 minutes (remove
    # $SCALE_DIR/ref-* to render them again).
    key=$(content_key "$v" "$SCALE_DIR/$1.nvdb" -- "scale-ref $2 $("$HAZE" --version 2>&1)")
    ref=$SCALE_DIR/ref-$1-$key.exr
    if [ ! -f "$ref" ]; then
        echo "  reference $1: volpath maxdepth 1, $2 spp" >&2
        "$HAZE" render "$v" --spp "$2" --threads "$THREADS" --seed 4321 -o "$ref.tmp.exr" --quiet --stats >"$ref.stats" 2>>"$LOG" ||
            { echo "bench: the reference of $1 failed" >&2; exit 1; }
        mv "$ref.tmp.exr" "$ref"
    fi
    look=$(awk '$1 == "stat" && $2 == "density_lookups_per_pixel" { print $3 }' "$ref.stats")
    awk -v l="${look:-0}" 'BEGIN { exit !(l > 0) }' || { echo "bench: $1: no density lookups (--stats: ${look:-none})" >&2; exit 1; }
    # The medium shows: the image is far from the same scene without it.
    grep -v -e MakeNamedMedium -e MediumInterface -e '"rgb sigma_a"' "$v" >"$SCALE_DIR/run/empty.pbrt"
    "$HAZE" render "$SCALE_DIR/run/empty.pbrt" --spp 1 --threads "$THREADS" -o "$SCALE_DIR/run/empty.exr" --quiet 2>>"$LOG" ||
        { echo "bench: $1: the scene without its medium failed" >&2; exit 1; }
    c=$(errors "$ref" "$SCALE_DIR/run/empty.exr" | cut -d' ' -f2)
    awk -v e="$c" 'BEGIN { exit !(e > 0.01) }' || { echo "bench: $1: the medium does not show (relMSE $c against the scene without it)" >&2; exit 1; }
    echo "$ref"
}

# scale_unbiased VOLUME RUN TARGET E: an unbiased renderer (RUN: volpath,
# haze's; pbrt-v4, $PBRT) at equal error: $scale_pilot_spp samples give the
# error of one, e1 (relMSE falls as 1/spp), then the spp that reaches TARGET
# (net relMSE) is timed and measured.
scale_unbiased() {
    d=$SCALE_DIR/run
    if [ "$2" = volpath ]; then
        set -- "$1" "$2" "$3" "$4" "$HAZE" render "$d/vp.pbrt" --threads "$THREADS" --seed 1 --quiet -o
    else
        set -- "$1" "$2" "$3" "$4" "$PBRT" "$d/pbrt.pbrt" --nthreads "$THREADS" --seed 1 --quiet --outfile
    fi
    v=$1 run=$2 target=$3 te=$4
    shift 4
    "$@" "$d/pilot.exr" --spp "$scale_pilot_spp" >>"$LOG" 2>&1 || { echo "bench: $v $run: the pilot failed" >&2; return 0; }
    ep=$(errors "$d/pilot.exr" "$ref" | cut -d' ' -f2)
    e1=$(awk -v e="$ep" -v n="$scale_pilot_spp" -v r="$scale_ref_spp" 'BEGIN { print e / (1 / n + 1 / r) }')
    n=$(awk -v e1="$e1" -v t="$target" 'BEGIN { n = e1 / t; n = n == int(n) ? n : int(n) + 1; print n < 1 ? 1 : (n > 1048576 ? 1048576 : n) }')
    scale_run_one "$d/r" "$@" "$d/u.exr" --spp "$n"
    e=-
    [ "$(scale_field "$d/r" 3)" = ok ] && e=$(scale_net "$(errors "$d/u.exr" "$ref" | cut -d' ' -f2)")
    # Sobol' samples converge faster than 1/spp where the image is smooth:
    # when the run missed the target by over 25%, once more at the count a
    # power law through the pilot and this run gives.
    if [ "$e" != - ] && awk -v e="$e" -v t="$target" 'BEGIN { exit !(e > 0 && (e < 0.8 * t || e > 1.25 * t)) }'; then
        n=$(awk -v p="$scale_pilot_spp" -v ep="$(scale_net "$ep")" -v n="$n" -v e="$e" -v t="$target" 'BEGIN {
            b = (ep > 0 && e > 0 && n > p) ? log(ep / e) / log(n / p) : 1
            if (b < 0.5) b = 0.5; if (b > 2) b = 2
            m = n * exp(log(e / t) / b); m = m == int(m) ? m : int(m) + 1
            print m < 1 ? 1 : (m > 1048576 ? 1048576 : m) }')
        scale_run_one "$d/r" "$@" "$d/u.exr" --spp "$n"
        e=-
        [ "$(scale_field "$d/r" 3)" = ok ] && e=$(scale_net "$(errors "$d/u.exr" "$ref" | cut -d' ' -f2)")
    fi
    mean=-
    [ "$e" != - ] && mean=$("$HAZE" diff "$d/u.exr" "$ref" --channels R,G,B | awk '$1 == "all" { printf "%+.2f%%", 100 * $(NF - 2) }')
    scale_row "$v" "$run" "$te" "$d/r" "$e" "$n" "equal error: $target (1 spp: $(awk -v e="$e1" 'BEGIN { printf "%.3g", e }')), mean $mean"
}

# scale_volume_run NAME: loading, the reference, then every error.
scale_volume_run() {
    scale_volume "$1"
    scale_loading "$1"
    ref=$(scale_reference "$1" "$scale_ref_spp") || exit 1
    d=$SCALE_DIR/run
    # The reference's own error: e(16) = e1 (1/16 + 1/REF_SPP).
    scale_scene "$d/vp.pbrt" "$1" "$SCALE_DIR/$1.nvdb" 'Integrator "volpath" "integer maxdepth" 1'
    "$HAZE" render "$d/vp.pbrt" --spp 16 --threads "$THREADS" --seed 1 -o "$d/floor.exr" --quiet >>"$LOG" 2>&1 || { echo "bench: volpath of $1 failed" >&2; exit 1; }
    scale_floor=$(errors "$d/floor.exr" "$ref" | awk -v r="$scale_ref_spp" '{ print $2 / (1 + 16 / r) * 16 / r }')
    printf '%s\treference\t-\t-\t-\tok\t%s\t%s\tthe reference'"'"'s own relMSE (volpath maxdepth 1)\n' "$1" "$scale_floor" "$scale_ref_spp" >>"$RESULTS/scale.tsv"
    scale_scene "$d/default.pbrt" "$1" "$SCALE_DIR/$1.nvdb" ""
    [ -n "${PBRT:-}" ] && scale_scene "$d/pbrt.pbrt" "$1" "$SCALE_DIR/$1.nvdb" 'Integrator "volpath" "integer maxdepth" 1'
    for te in $SCALE_ERRORS; do
        scale_run_one "$d/r" "$HAZE" render "$d/default.pbrt" --target-error "$te" --threads "$THREADS" --seed 1 -o "$d/default.exr" --stats
        e=- m=- note=
        if [ "$(scale_field "$d/r" 3)" = ok ]; then
            e=$(scale_net "$(errors "$d/default.exr" "$ref" | cut -d' ' -f2)")
            m=$("$HAZE" info "$d/default.exr" | awk '$1 == "haze:spp_mean" { gsub(/"/, "", $3); print $3 }')
            note="pilot $(awk '$1 == "stat" && $2 == "time_pilot_s" { t = $3 } $1 == "stat" && $2 == "cpu_pilot_majorant_build_s" { c = $3 }
                END { printf "%s s", t; if (c > 0) printf " (cells %s CPU s)", c }' "$d/r.out"), steps $("$HAZE" info "$d/default.exr" | awk '$1 == "haze:stepsize" { $1 = $2 = ""; gsub(/"/, ""); sub(/^ +/, ""); print }')"
        fi
        scale_row "$1" default "$te" "$d/r" "$e" "$m" "$note"
        # Equal error: what the default reached (E itself when it timed out).
        target=$te
        [ "$e" != - ] && awk -v e="$e" 'BEGIN { exit !(e > 0) }' && target=$e
        scale_unbiased "$1" volpath "$target" "$te"
        [ -z "${PBRT:-}" ] || scale_unbiased "$1" pbrt-v4 "$target" "$te"
    done
}

scale_run() {
    [ -x /usr/bin/time ] || { echo "bench: the scale part needs GNU time (/usr/bin/time)" >&2; exit 1; }
    mkdir -p "$SCALE_DIR"
    printf 'volume\trun\tE\tseconds\tpeak_kib\tstatus\trelmse\tspp\tnote\n' >"$RESULTS/scale.tsv"
    if [ -n "$BENCH_QUICK" ]; then
        rs="25 50" scale_ref_spp=256
    else
        rs="25 50 100 200 400" scale_ref_spp=4096
    fi
    max=${BENCH_SCALE_MAX_R:-400}
    for r in $rs; do
        [ "$r" -le "$max" ] && scale_volume_run "sphere-$r"
    done
    [ -z "$BENCH_QUICK" ] && [ -z "${BENCH_SCALE_NO_SPARSE:-}" ] && scale_volume_run sparse
    scale_report
}

# scale_get VOLUME RUN E FIELD: one field of a row of scale.tsv (empty if none).
scale_get() {
    awk -F'\t' -v v="$1" -v r="$2" -v e="$3" -v f="$4" \
        'NR > 1 && $1 == v && $2 == r && $3 == e { x = $f } END { print x }' "$RESULTS/scale.tsv"
}

# scale_time VOLUME RUN E: "12.3" or "> 300" (timed out) or "failed".
scale_time() {
    case $(scale_get "$1" "$2" "$3" 6) in
    ok) scale_get "$1" "$2" "$3" 4 ;;
    timeout) echo "> $SCALE_TIMEOUT" ;;
    "") echo - ;;
    *) echo failed ;;
    esac
}

scale_mib() { awk -v k="$1" 'BEGIN { if (k == "") print "-"; else printf "%.1f", k / 1024 }'; }

# scale_ratio A B: A / B to 2 decimals ("> x" when A is "> a": timed out),
# "-" unless both are numbers.
scale_ratio() {
    awk -v a="$1" -v b="$2" 'BEGIN {
        gt = a ~ /^>/; sub(/^> */, "", a)
        if (a ~ /^[0-9.]+$/ && b ~ /^[0-9.]+$/ && b > 0) printf "%s%.2f", gt ? "> " : "", a / b; else print "-" }'
}

scale_report_loading() {
    echo "## Loading"
    echo
    echo "Whole processes, warm page cache. *read* is \`cat FILE > /dev/null\`; *load* a"
    echo "one-pixel render (\`--pixelbounds 0,1,0,1 --spp 1\`: start-up, parsing, the grid"
    echo "read and checked, the majorant grid, the output). Peak is GNU time's maximum"
    echo "resident set (for the .vdb: haze or its reader process, whichever is larger)."
    echo "Targets: load time ≤ 1.5x read, and the .nvdb's peak ≤ 1.2x the file + the film (0.9 MiB)."
    echo
    echo "| volume | .nvdb MiB | read s | haze info s | load s | load / read | peak MiB | peak / (file + film) | .vdb MiB | .vdb converting s | peak MiB | .vdb cached s | peak MiB |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    for v in $(awk -F'\t' 'NR > 1 && $2 == "load .nvdb" { print $1 }' "$RESULTS/scale.tsv"); do
        mb=$(scale_get "$v" "cat .nvdb" - 9 | cut -d' ' -f1)
        vmb=$(scale_get "$v" "load .vdb converting" - 9 | cut -d' ' -f1)
        rd=$(scale_time "$v" "cat .nvdb" -) ld=$(scale_time "$v" "load .nvdb" -)
        pk=$(scale_mib "$(scale_get "$v" "load .nvdb" - 5)")
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$v" "$mb" "$rd" \
            "$(scale_time "$v" "haze info .nvdb" -)" "$ld" "$(scale_ratio "$ld" "$rd")" "$pk" \
            "$(awk -v p="$pk" -v m="$mb" 'BEGIN { printf "%.2f", p / (m + 0.9) }')" "$vmb" \
            "$(scale_time "$v" "load .vdb converting" -)" "$(scale_mib "$(scale_get "$v" "load .vdb converting" - 5)")" \
            "$(scale_time "$v" "load .vdb cached" -)" "$(scale_mib "$(scale_get "$v" "load .vdb cached" - 5)")"
    done
    echo
}

scale_report_error() {
    te=$1
    echo "## --target-error $te"
    echo
    echo "*default*: \`haze render --target-error $te\` with the scene's default integrator"
    echo "(singlescatter); *− load* subtracts the one-pixel render of the loading table;"
    echo "*pilot, steps*: the step pilot's time (\`--stats\` time_pilot_s; *cells*: the CPU seconds of"
    echo "the majorant cells it was first to reach, which the render would build otherwise) and the steps it"
    echo "chose. *volpath*: \`Integrator \"volpath\" \"integer maxdepth\" 1\`, and *pbrt-v4* the"
    echo "same in pbrt-v4, each at the samples per pixel that reach the relMSE the default"
    echo "reached (E when it timed out): $scale_pilot_spp samples give the error of one, the run at"
    echo "that count is timed and measured, and run again once at a corrected count when it"
    echo "missed by over 25%. relMSE is against the volume's reference, less the reference's"
    echo "own error; *mean* is the image mean against the reference's."
    echo
    echo "| volume | default s | − load s | peak MiB | relMSE | spp mean | pilot, steps | volpath spp | s | relMSE | pbrt-v4 spp | s | relMSE | mean | default / pbrt-v4 |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    for v in $(awk -F'\t' -v e="$te" 'NR > 1 && $2 == "default" && $3 == e { print $1 }' "$RESULTS/scale.tsv"); do
        t=$(scale_time "$v" default "$te") ld=$(scale_get "$v" "load .nvdb" - 4)
        tl=$(awk -v t="$t" -v l="$ld" 'BEGIN { if (t ~ /^[0-9.]+$/) printf "%.3f", t - l; else print t }')
        tp=$(scale_time "$v" pbrt-v4 "$te")
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$v" "$t" "$tl" \
            "$(scale_mib "$(scale_get "$v" default "$te" 5)")" "$(scale_get "$v" default "$te" 7)" \
            "$(scale_get "$v" default "$te" 8)" "$(scale_get "$v" default "$te" 9 | sed 's/^$/-/')" \
            "$(scale_get "$v" volpath "$te" 8)" "$(scale_time "$v" volpath "$te")" "$(scale_get "$v" volpath "$te" 7)" \
            "$(scale_get "$v" pbrt-v4 "$te" 8 | sed 's/^$/-/')" "$tp" "$(scale_get "$v" pbrt-v4 "$te" 7 | sed 's/^$/-/')" \
            "$(scale_get "$v" pbrt-v4 "$te" 9 | sed -n 's/.*mean //p' | sed 's/^$/-/')" "$(scale_ratio "$t" "$tp")"
    done
    echo
}

# scale_ratio_400 E: the default's time(R=400) / time(R=25), loading
# excluded ("> x" when R=400 timed out; "-" without both).
scale_ratio_400() {
    t25=$(scale_time sphere-25 default "$1") l25=$(scale_get sphere-25 "load .nvdb" - 4)
    t400=$(scale_time sphere-400 default "$1") l400=$(scale_get sphere-400 "load .nvdb" - 4)
    awk -v a="$t400" -v la="$l400" -v b="$t25" -v lb="$l25" 'BEGIN {
        gt = a ~ /^>/; sub(/^> */, "", a)
        if (a !~ /^[0-9.]+$/ || b !~ /^[0-9.]+$/ || b - lb <= 0) { print "-"; exit }
        printf "%s%.1f", gt ? "> " : "", (a - la) / (b - lb) }'
}

# scale_verdict VALUE OP LIMIT: met, missed, or "-" when VALUE is not known.
scale_verdict() {
    awk -v v="$1" -v op="$2" -v l="$3" 'BEGIN {
        gt = v ~ /^>/; sub(/^> */, "", v)
        if (v !~ /^[0-9.]+$/) { print "-"; exit }
        ok = op == "le" ? (v <= l && !gt) : v >= l
        print ok ? "met" : "**missed**" }'
}

scale_report_targets() {
    echo "## Targets (issue 43)"
    echo
    echo "| target | measured | |"
    echo "|---|---|---|"
    for te in $SCALE_ERRORS; do
        r=$(scale_ratio_400 "$te")
        echo "| default at E = $te: time(R=400) / time(R=25), loading excluded, ≤ 3 | $r | $(scale_verdict "$r" le 3) |"
    done
    for v in $(awk -F'\t' 'NR > 1 && $2 == "load .nvdb" { print $1 }' "$RESULTS/scale.tsv"); do
        rd=$(scale_time "$v" "cat .nvdb" -) ld=$(scale_time "$v" "load .nvdb" -)
        r=$(scale_ratio "$ld" "$rd")
        mb=$(scale_get "$v" "cat .nvdb" - 9 | cut -d' ' -f1)
        p=$(awk -v p="$(scale_mib "$(scale_get "$v" "load .nvdb" - 5)")" -v m="$mb" 'BEGIN { printf "%.2f", p / (m + 0.9) }')
        awk -v m="$mb" 'BEGIN { exit !(m >= 100) }' || continue
        echo "| $v: load ≤ 1.5x reading the file | $r ($ld s / $rd s) | $(scale_verdict "$r" le 1.5) |"
        echo "| $v: peak ≤ 1.2x (file + film) | $p | $(scale_verdict "$p" le 1.2) |"
    done
    if [ -n "${PBRT:-}" ] || awk -F'\t' 'NR > 1 && $2 == "pbrt-v4" { f = 1 } END { exit !f }' "$RESULTS/scale.tsv"; then
        for te in $SCALE_ERRORS; do
            worst=$(for v in $(awk -F'\t' -v e="$te" 'NR > 1 && $2 == "default" && $3 == e { print $1 }' "$RESULTS/scale.tsv"); do
                scale_ratio "$(scale_time "$v" default "$te")" "$(scale_time "$v" pbrt-v4 "$te")"; echo; done | grep -v '^-' | sort -g | tail -1)
            echo "| default at E = $te ≤ 0.5x pbrt-v4's time at equal error, every volume (the worst) | ${worst:--} | $(scale_verdict "${worst:--}" le 0.5) |"
        done
    fi
    echo
    echo "Loading targets are listed for files of 100 MiB and more (smaller ones load in"
    echo "less time than the process takes to start)."
    echo
}

scale_report() {
    {
        echo "# Scale: cost against the grid's resolution"
        echo
        echo "Written by \`make bench\` (the scale part, bench/scale.sh)$([ -n "$BENCH_QUICK" ] && echo " with BENCH_QUICK=1") on $(date -u '+%Y-%m-%d %H:%M UTC'),"
        echo "$(nproc) CPUs, load average before the run $BENCH_LOAD, $THREADS render threads,"
        echo "runs cut at $SCALE_TIMEOUT s (BENCH_SCALE_TIMEOUT), $(haze_id)."
        echo "Each time is one whole process (the median of three when under 2 s)."
        echo "bench/README.md describes the volumes and the scenes."
        echo
        scale_report_targets
        scale_report_loading
        for te in $SCALE_ERRORS; do
            scale_report_error "$te"
        done
        echo "## References"
        echo
        echo "| volume | spp | own relMSE |"
        echo "|---|---|---|"
        awk -F'\t' 'NR > 1 && $2 == "reference" { printf "| %s | %s | %.3g |\n", $1, $8, $7 }' "$RESULTS/scale.tsv"
    } >"$RESULTS/scale.md"
}
