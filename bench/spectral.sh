#!/bin/sh
# The spectral part (bench/README.md, issue 44): what rendering colour as
# wavelengths costs against RGB, and which of the two lands nearer pbrt-v4.
# For each scene (bench scenes under volpath, the colour stand-ins of
# tests/standins, and bench/scenes/spectral/: one scene per case of the
# issue), in each mode (--color rgb, --color spectral):
#   - a reference at high spp (cached), its own mode's converged image;
#   - two rungs at N and 4N spp (seed 1) under GNU time: CPU seconds
#     (user + sys, robust to the machine's other load) and wall seconds, and
#     the error against the mode's reference: MSE over R, G, B divided by the
#     reference's mean squared (nMSE; haze diff's per-pixel relMSE divides
#     by (b + 0.01)^2, which vanishes where a spectral image has a component
#     near -0.01: saturated colours outside sRGB);
#   - the error of one sample e1 = nMSE(4N) / (1/4N + 1/REF) (the error falls
#     as 1/spp; the reference's own noise removed), the time model
#     t(n) = t0 + ts n through the two rungs, and so the time to reach an
#     nMSE E: t0 + ts e1 / E, for E = 1e-2 and 1e-3;
# and with PBRT= (a pbrt-v4 binary), pbrt-v4's image of the same file, whose
# per-channel means each mode's reference is divided by. Writes
# $RESULTS/spectral.tsv and $RESULTS/spectral.md.
# Sourced by bench/run.sh (needs lib.sh and its variables).

SPECTRAL_DIR=$CACHE/spectral
SPECTRAL_DATA=${HAZE_SPECTRAL_DATA:-$(dirname "$HAZE")/bench/haze_spectral_data}
SPECTRAL_ERRORS="1e-2 1e-3"
TOP=$(cd "$BENCH/.." && pwd)

# The scenes: NAME KIND SOURCE MAXDEPTH SCALE REF_SPP N PBRT_SPP. KIND bench:
# SOURCE (no Integrator) under `Integrator "volpath" "integer maxdepth"
# MAXDEPTH`; standin: a copy of tests/standins/SOURCE beside its data, its
# resolution times SCALE, its own Integrator (sppm becomes volpath at its
# maxdepth). Rungs at N and 4N spp; the reference at REF_SPP; pbrt-v4 at
# PBRT_SPP. Sizes chosen for the whole part to take about 12 minutes on 2
# shared cores with no reference cached.
spectral_scenes() {
    cat <<'EOF'
surfaces bench bench/scenes/surfaces.pbrt 8 1 32 2 8
fog-room bench bench/scenes/fog-room.pbrt 16 1 64 4 16
cloud bench bench/scenes/cloud.pbrt 32 1 32 2 8
streetlight-fog bench bench/scenes/spectral/streetlight-fog.pbrt 16 1 128 8 32
gold-killeroo bench bench/scenes/spectral/gold-killeroo.pbrt 16 1 256 16 64
saturated-room bench bench/scenes/spectral/saturated-room.pbrt 16 1 128 8 32
glass-tank bench bench/scenes/spectral/glass-tank.pbrt 16 1 256 16 64
crown standin crown.pbrt 100 5 256 16 64
killeroo-simple standin killeroo-simple.pbrt 5 4 256 16 64
contemporary-bathroom standin contemporary-bathroom.pbrt 5 4 256 16 64
bunny-cloud standin bunny-cloud.pbrt 50 3 128 8 32
EOF
}

# spectral_stage: the stand-ins and the data they name (made by
# haze_spectral_data, as tests/render/test_standins.c makes them) in
# $SPECTRAL_DIR/standins.
spectral_stage() {
    s=$SPECTRAL_DIR/standins
    mkdir -p "$s/textures" "$s/geometry"
    [ -x "$SPECTRAL_DATA" ] || { echo "bench: $SPECTRAL_DATA is not built (cmake --build build)" >&2; exit 1; }
    [ -f "$s/textures/sky.exr" ] || "$SPECTRAL_DATA" "$s" >>"$LOG" 2>&1 ||
        { echo "bench: haze_spectral_data failed" >&2; exit 1; }
    cp "$TOP/volumes/box.nvdb" "$s/bunny_cloud.nvdb"
    cp "$TOP"/tests/standins/geometry/* "$s/geometry/"
}

# spectral_standin NAME FILE SCALE MAXDEPTH: prints the path of the staged
# copy of tests/standins/FILE: resolution times SCALE, sppm as volpath.
spectral_standin() {
    out=$SPECTRAL_DIR/standins/$1-bench.pbrt
    awk -v f="$3" '
        /^Integrator "sppm"/ { sub(/"sppm"/, "\"volpath\"") }
        /"float radius" 0.02/ && sppm_radius == 0 { sppm_radius = 1; next }
        {
            for (k = 0; k < 2; k++) {
                key = k ? "\"integer yresolution\"" : "\"integer xresolution\""
                if (i = index($0, key)) {
                    rest = substr($0, i + length(key))
                    match(rest, /[0-9]+/)
                    n = substr(rest, RSTART, RLENGTH) * f
                    $0 = substr($0, 1, i + length(key) - 1) substr(rest, 1, RSTART - 1) n substr(rest, RSTART + RLENGTH)
                }
            }
            print
        }' "$TOP/tests/standins/$2" >"$out"
    echo "$out"
}

# spectral_top NAME KIND SOURCE MAXDEPTH SCALE: prints the file haze and
# pbrt-v4 render for the scene: a wrapper in $CACHE (where the bench scenes'
# relative paths resolve) or the staged stand-in.
spectral_top() {
    case $2 in
    bench)
        v=$CACHE/spectral-$1.pbrt
        variant "$v" "$TOP/$3" "Integrator \"volpath\" \"integer maxdepth\" $4"
        echo "$v" ;;
    standin) spectral_standin "$1" "$3" "$5" "$4" ;;
    esac
}

# spectral_pbrt_top TOP: pbrt-v4's copy of TOP with .vdb grids as .nvdb
# (converted once with nanovdb_convert), beside TOP so relative paths hold.
spectral_pbrt_top() {
    # A bench wrapper Includes the scene: inline it for the rewrite.
    inc=$(awk '$1 == "Include" && $2 ~ /^"\// && !n++ { gsub(/"/, "", $2); print $2 }' "$1")
    src=$1
    [ -n "$inc" ] && src=$inc
    grep -q '\.vdb"' "$src" || { echo "$1"; return 0; }
    base=${1%.pbrt}
    : >"$base.convert"
    sdir=$(dirname "$1")
    {
        [ -n "$inc" ] && grep -v '^Include ' "$1"
        awk -v sdir="$sdir" -v d="$SPECTRAL_DIR" -v list="$base.convert" '{
            while (match($0, /"[^"]*\.vdb"/)) {
                f = substr($0, RSTART + 1, RLENGTH - 2)
                p = (f ~ /^\//) ? f : sdir "/" f
                n = split(f, parts, "/"); o = d "/" parts[n]; sub(/\.vdb$/, ".nvdb", o)
                print p " " o > list
                $0 = substr($0, 1, RSTART - 1) "\"" o "\"" substr($0, RSTART + RLENGTH)
            }
            print
        }' "$src"
    } >"$base-pbrt.pbrt"
    while read -r p o; do
        [ -f "$o" ] || nanovdb_convert -f "$p" "$o" >>"$LOG" 2>&1 ||
            { echo "bench: nanovdb_convert $p failed" >&2; exit 1; }
    done <"$base.convert"
    echo "$base-pbrt.pbrt"
}

# spectral_errors A.exr REF.exr: "NMSE RELMSE" over R, G, B (NMSE: MSE over
# REF's mean squared).
spectral_errors() {
    "$HAZE" diff "$1" "$2" --channels R,G,B | awk '$1 == "all" { printf "%.6g %s\n", $2 / ($(NF - 3) * $(NF - 3)), $4; found = 1 } END { exit !found }' ||
        { echo "bench: haze diff $1 $2 failed" >&2; exit 1; }
}

# spectral_means A.exr B.exr: "R G B" means of A over B's.
spectral_means() {
    "$HAZE" diff "$1" "$2" --channels R,G,B | awk '
        $1 == "R" || $1 == "G" || $1 == "B" { r[$1] = ($(NF - 3) != 0) ? $(NF - 4) / $(NF - 3) : 0 }
        END { if (length(r) != 3) exit 1; printf "%.4f %.4f %.4f\n", r["R"], r["G"], r["B"] }' ||
        { echo "bench: haze diff $1 $2 failed" >&2; exit 1; }
}

# spectral_pbrt TOP SPP OUT.exr: pbrt-v4 renders TOP (it crashes now and then
# at start-up with 2 threads: up to 5 tries). Prints its wall seconds.
spectral_pbrt() {
    for try in 1 2 3 4 5; do
        rm -f "$3"
        t0=$(now)
        if "$PBRT" --nthreads "$THREADS" --spp "$2" --seed 1 --quiet --outfile "$3" "$1" >>"$LOG" 2>&1 && [ -f "$3" ]; then
            elapsed "$t0" "$(now)"
            return 0
        fi
        echo "  pbrt-v4 try $try failed" >&2
    done
    echo "bench: pbrt-v4 failed 5 times on $1" >&2
    return 1
}

# spectral_auto TOP: the mode --color auto picks ("spectral" or "rgb").
spectral_auto() {
    "$HAZE" render "$1" --spp 1 --threads "$THREADS" --pixelbounds 0,1,0,1 --stats --quiet \
        -o "$SPECTRAL_DIR/auto.exr" 2>&1 | awk '$1 == "stat" && $2 == "spectral" && $3 == 1 { s = 1 } END { print s ? "spectral" : "rgb" }'
}

# spectral_mode NAME TOP MODE REF_SPP N: the reference, the two rungs and
# the fit; appends a row to spectral.tsv and prints the reference's path.
spectral_mode() {
    name=$1 top=$2 mode=$3 rs=$4 n1=$5
    n2=$((4 * n1))
    key=$(cache_key "$top" -- "spectral-ref $mode $rs")
    ref=$SPECTRAL_DIR/ref-$name-$mode-$key.exr
    if [ ! -f "$ref" ]; then
        echo "  reference $name $mode: $rs spp" >&2
        "$HAZE" render "$top" --color "$mode" --spp "$rs" --threads "$THREADS" --seed 4321 -o "$ref.tmp.exr" --quiet >>"$LOG" 2>&1 ||
            { echo "bench: the reference of $name ($mode) failed" >&2; exit 1; }
        mv "$ref.tmp.exr" "$ref"
    fi
    r=$SPECTRAL_DIR/run
    for n in $n1 $n2; do
        cpu_timed "$r-$n" 2 "$HAZE" render "$top" --color "$mode" --spp "$n" --threads "$THREADS" --seed 1 -o "$r-$n.exr" --quiet
        spectral_errors "$r-$n.exr" "$ref" >"$r-$n.err"
    done
    awk -v n1="$n1" -v n2="$n2" -v rs="$rs" -v e1="$(cut -d' ' -f1 "$r-$n1.err")" -v e2="$(cut -d' ' -f1 "$r-$n2.err")" \
        -v rel="$(cut -d' ' -f2 "$r-$n2.err")" \
        -v c1="$(cut -d' ' -f1 "$r-$n1")" -v c2="$(cut -d' ' -f1 "$r-$n2")" \
        -v w1="$(cut -d' ' -f2 "$r-$n1")" -v w2="$(cut -d' ' -f2 "$r-$n2")" \
        -v name="$name" -v mode="$mode" -v errs="$SPECTRAL_ERRORS" 'BEGIN {
        # The reference shares the estimator: relMSE(n) = e1 (1/n + 1/rs).
        one = e2 / (1 / n2 + 1 / rs)
        # The slope between the rungs, net of the reference (1: 1/spp).
        a = e1 - one / rs; b = e2 - one / rs
        slope = (a > 0 && b > 0) ? log(a / b) / log(n2 / n1) : 0
        ts = (c2 - c1) / (n2 - n1); t0 = c1 - ts * n1
        if (ts <= 0) { ts = c2 / n2; t0 = 0 }
        if (t0 < 0) { t0 = 0; ts = c2 / n2 }
        printf "%s\t%s\t%d\t%d\t%d\t%.4g\t%.4g\t%.3f\t%.3f\t%.3f\t%.3f\t%.4g\t%.3f\t%.4g\t%.3f\t%.4g", name, mode, rs, n1, n2, e1, e2, c1, c2, w1, w2, one, slope, ts, t0, rel
        k = split(errs, E, " ")
        for (i = 1; i <= k; i++) printf "\t%.4g", t0 + ts * one / E[i]
        printf "\n"
    }' >>"$RESULTS/spectral.tsv"
    tail -1 "$RESULTS/spectral.tsv" | awk -F'\t' '{ printf "  %s %s: nMSE %s at %s spp, %s at %s (relMSE %s); %s / %s cpu s; e1 %s, slope %s; time at 1e-2 %s s, 1e-3 %s s\n", $1, $2, $6, $4, $7, $5, $16, $8, $9, $12, $13, $17, $18 }' >&2
    echo "$ref"
}

# spectral_scene NAME KIND SOURCE MAXDEPTH SCALE REF_SPP N PBRT_SPP
spectral_scene() {
    top=$(spectral_top "$1" "$2" "$3" "$4" "$5")
    auto=$(spectral_auto "$top")
    echo "  $1: auto picks $auto" >&2
    ref_rgb=$(spectral_mode "$1" "$top" rgb "$6" "$7") || exit 1
    ref_spec=$(spectral_mode "$1" "$top" spectral "$6" "$7") || exit 1
    m_rgb=- m_spec=- pt=-
    if [ -n "${PBRT:-}" ]; then
        p=$SPECTRAL_DIR/pbrt-$1.exr
        if pt=$(spectral_pbrt "$(spectral_pbrt_top "$top")" "$8" "$p"); then
            m_rgb=$(spectral_means "$ref_rgb" "$p" | tr ' ' ,)
            m_spec=$(spectral_means "$ref_spec" "$p" | tr ' ' ,)
        else
            pt=failed
        fi
    fi
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$auto" "$8" "$pt" "$m_rgb" "$m_spec" >>"$RESULTS/spectral-pbrt.tsv"
    echo "  $1 against pbrt-v4 ($8 spp, $pt s): means rgb $m_rgb, spectral $m_spec" >&2
}

spectral_run() {
    [ -x /usr/bin/time ] || { echo "bench: the spectral part needs GNU time (/usr/bin/time)" >&2; exit 1; }
    mkdir -p "$SPECTRAL_DIR"
    spectral_stage
    printf 'scene\tmode\tref_spp\tn1\tn2\tnmse1\tnmse2\tcpu1\tcpu2\twall1\twall2\te1\tslope\tcpu_per_spp\tcpu0\trelmse2\ttime_1e-2\ttime_1e-3\n' >"$RESULTS/spectral.tsv"
    printf 'scene\tauto\tpbrt_spp\tpbrt_s\trgb_over_pbrt\tspectral_over_pbrt\n' >"$RESULTS/spectral-pbrt.tsv"
    spectral_scenes | while read -r name kind src depth scale rs n ps; do
        case " ${BENCH_SPECTRAL_SCENES:-$name} " in *" $name "*) ;; *) continue ;; esac
        # BENCH_QUICK: a quarter of the samples everywhere.
        if [ -n "$BENCH_QUICK" ]; then
            rs=$((rs / 4)) ps=$((ps / 4)) n=$(((n + 3) / 4))
        fi
        spectral_scene "$name" "$kind" "$src" "$depth" "$scale" "$rs" "$n" "$ps"
    done
    spectral_report
}

# spectral_report: $RESULTS/spectral.md from the two tables.
spectral_report() {
    md=$RESULTS/spectral.md
    {
        echo "# Spectral against RGB rendering (bench/spectral.sh)"
        echo
        echo "Written by \`BENCH_PARTS=spectral make bench\` on $(date -u +%Y-%m-%d), $("$HAZE" --version 2>&1),"
        echo "$THREADS threads, load average before the run $BENCH_LOAD. Each mode against its own"
        echo "reference (seed 4321; rungs at N and 4N spp, seed 1). The error is nMSE: the MSE"
        echo "over R, G, B divided by the reference's mean squared (haze diff's per-pixel relMSE"
        echo "divides by (b + 0.01)², which vanishes where a spectral image has a component near"
        echo "-0.01, as saturated colours outside sRGB do). *e1*: the nMSE of one sample per pixel"
        echo "(nMSE(4N) / (1/4N + 1/REF)); *ms/spp*: CPU (user + sys) per sample per pixel over"
        echo "the image, from the two rungs; *t(E)*: CPU seconds to reach nMSE E (start-up +"
        echo "ms/spp · e1 / E); *x*: spectral / RGB at equal error."
        echo "*/pbrt*: each mode's reference's R, G, B means over pbrt-v4's image of the same file"
        [ -n "${PBRT:-}" ] && echo "($PBRT, spp per scene in spectral-pbrt.tsv)." || echo "(not run: PBRT unset)."
        echo
        echo "| scene | auto | e1 RGB | e1 spectral | ms/spp RGB | ms/spp spectral | t(1e-2) RGB | spectral | x | t(1e-3) RGB | spectral | x | haze-RGB / pbrt | haze-spectral / pbrt |"
        echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        awk -F'\t' '
            FNR == 1 { next }
            FILENAME ~ /spectral-pbrt\.tsv$/ { auto[$1] = $2; mr[$1] = $5; ms[$1] = $6; next }
            { k = $1 SUBSEP $2; e1[k] = $12; tps[k] = $14; t2[k] = $17; t3[k] = $18; if (!($1 in seen)) { seen[$1] = 1; order[++n] = $1 } }
            END {
                for (i = 1; i <= n; i++) {
                    s = order[i]; r = s SUBSEP "rgb"; p = s SUBSEP "spectral"
                    x2 = t2[p] / t2[r]; x3 = t3[p] / t3[r]
                    gsub(/,/, " ", mr[s]); gsub(/,/, " ", ms[s])
                    printf "| %s | %s | %.3g | %.3g | %.2f | %.2f | %.3g | %.3g | %.2f | %.3g | %.3g | %.2f | %s | %s |\n",
                        s, auto[s], e1[r], e1[p], 1000 * tps[r], 1000 * tps[p], t2[r], t2[p], x2, t3[r], t3[p], x3, mr[s], ms[s]
                    l3 = log(x3); all += l3; na++
                    if (auto[s] == "spectral") { sp += l3; ns++ }
                    if (x3 > mx) { mx = x3; mxs = s }
                    if (x3 <= 1.2) ok++
                    # Further from pbrt-v4: the largest channel error of each mode.
                    if (mr[s] != "-" && ms[s] != "-") {
                        split(mr[s], a, " "); split(ms[s], b, " "); da = db = 0
                        for (c = 1; c <= 3; c++) { if ((v = a[c] - 1) < 0) v = -v; if (v > da) da = v; if ((v = b[c] - 1) < 0) v = -v; if (v > db) db = v }
                        if (db > 0.02) far = far sprintf(" %s (spectral %.1f%% off, RGB %.1f%%);", s, 100 * db, 100 * da)
                        if (db > da + 0.005) worse = worse sprintf(" %s (%.1f%% against %.1f%%);", s, 100 * db, 100 * da)
                    }
                }
                printf "\nSpectral / RGB CPU time at nMSE 1e-3: geometric mean %.2f over all %d scenes", exp(all / na), na
                if (ns) printf ", %.2f over the %d that `--color auto` renders spectrally", exp(sp / ns), ns
                printf "; largest %.2f (%s); at most 1.2 on %d of %d.\n", mx, mxs, ok, na
                if (far != "") printf "\nSpectral more than 2%% from pbrt-v4 in a channel:%s\n", far
                if (worse != "") printf "\nSpectral further from pbrt-v4 than RGB by over 0.5%%:%s\n", worse
            }' "$RESULTS/spectral-pbrt.tsv" "$RESULTS/spectral.tsv"
    } >"$md"
    echo "  wrote $md" >&2
}
