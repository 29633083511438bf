# Shared helpers of the benchmark scripts (sourced, POSIX sh + awk).
# Expects: HAZE (the haze binary), BENCH (the bench/ directory), CACHE (the
# reference cache directory), THREADS.

# now: seconds since the epoch with nanoseconds (GNU date).
now() { date +%s.%N; }

# elapsed T0 T1: T1 - T0 in seconds, 3 decimals.
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", b - a }'; }

# cpu_timed OUT UNDER CMD...: CMD under GNU time; writes "cpu wall" seconds
# to OUT (cpu = user + sys of the whole process): the median of three runs,
# or of those until one takes UNDER seconds of wall or more (1e30: three).
cpu_timed() {
    ct_o=$1 ct_under=$2
    shift 2
    ct_cs= ct_ws=
    for _ in 1 2 3; do
        /usr/bin/time -f '%U %S %e' -o "$ct_o.time" "$@" >>"$LOG" 2>&1 ||
            { echo "bench: failed: $*" >&2; tail -5 "$LOG" >&2; exit 1; }
        ct_w=$(awk '{ print $3 }' "$ct_o.time")
        ct_cs="$ct_cs $(awk '{ printf "%.3f", $1 + $2 }' "$ct_o.time")" ct_ws="$ct_ws $ct_w"
        awk -v w="$ct_w" -v u="$ct_under" 'BEGIN { exit !(w < u) }' || break
    done
    printf '%s %s\n' "$(printf '%s\n' $ct_cs | median)" "$(printf '%s\n' $ct_ws | median)" >"$ct_o"
}

# median of the numbers on stdin.
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else printf "%.3f\n", (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

# timed CMD...: runs CMD (stdout and stderr to $LOG), prints its wall time in
# seconds; a failing command is fatal. Runs that take under 2 s are repeated
# (3 runs in all, 7 under 0.5 s) and the median printed.
timed() {
    t0=$(now)
    "$@" >>"$LOG" 2>&1 || { echo "bench: failed: $*" >&2; tail -5 "$LOG" >&2; exit 1; }
    t1=$(now)
    t=$(elapsed "$t0" "$t1")
    # Short runs vary most with the machine's load (10% between two runs of
    # 0.1 s): the median of 7 under 0.5 s, of 3 under 2 s.
    if awk -v t="$t" 'BEGIN { exit !(t < 2) }'; then
        ts=$t
        more="2 3"
        awk -v t="$t" 'BEGIN { exit !(t < 0.5) }' && more="2 3 4 5 6 7"
        for _ in $more; do
            t0=$(now); "$@" >>"$LOG" 2>&1; t1=$(now)
            ts="$ts $(elapsed "$t0" "$t1")"
        done
        t=$(printf '%s\n' $ts | median)
    fi
    echo "$t"
}

# errors A.exr REF.exr: prints "RMSE RELMSE" over R,G,B (haze diff's "all" row).
errors() {
    "$HAZE" diff "$1" "$2" --channels R,G,B | awk '$1 == "all" { print $3, $4; found = 1 } END { exit !found }' ||
        { echo "bench: haze diff $1 $2 failed" >&2; exit 1; }
}

# variant OUT.pbrt SCENE.pbrt INTEGRATOR-LINE: a scene file that sets the
# integrator and includes SCENE (whose relative paths stay relative to it).
variant() {
    printf '%s\nInclude "%s"\n' "$3" "$(cd "$(dirname "$2")" && pwd)/$(basename "$2")" >"$1"
}

# cached_reference SCENE NAME PREFIX KEYWORDS INTEGRATOR-LINE SPP SEED: the path
# of SCENE's reference rendered with INTEGRATOR-LINE at SPP, SEED, rendered
# once and cached in $CACHE/PREFIX-NAME-KEY.exr (KEY from the scene, KEYWORDS
# and haze_id).
cached_reference() {
    key=$(cache_key "$1" -- "$4")
    ref=$CACHE/$3-$2-$key.exr
    if [ ! -f "$ref" ]; then
        v=$CACHE/$3-$2.pbrt
        variant "$v" "$1" "$5"
        echo "  reference $2: $5, $6 spp (cached as $(basename "$ref"))" >&2
        t=$(timed "$HAZE" render "$v" --spp "$6" --threads "$THREADS" --seed "$7" -o "$ref.tmp.exr" --quiet)
        mv "$ref.tmp.exr" "$ref"
        echo "  reference $2 took $t s" >&2
    fi
    echo "$ref"
}

# integrator EST STEP: the Integrator line of one ladder rung (shadow step
# twice the camera-ray step, as haze's defaults 1 / 2).
integrator() {
    sstep=$(awk -v s="$2" 'BEGIN { print 2 * s }')
    # ESTIMATOR+cache: the shadow cache at the step's spacing (docs/media.md);
    # ESTIMATOR+finecache: at half of it (8x the nodes, the same lookup cost).
    case $1 in
    *+finecache) printf 'Integrator "singlescatter" "string transmittance" "%s" "float stepsize" %s "float shadowstepsize" %s "float shadowcache" %s' "${1%+finecache}" "$2" "$sstep" "$(awk -v s="$2" 'BEGIN { print s / 2 }')" ;;
    *+cache) printf 'Integrator "singlescatter" "string transmittance" "%s" "float stepsize" %s "float shadowstepsize" %s "float shadowcache" %s' "${1%+cache}" "$2" "$sstep" "$2" ;;
    *) printf 'Integrator "singlescatter" "string transmittance" "%s" "float stepsize" %s "float shadowstepsize" %s' "$1" "$2" "$sstep" ;;
    esac
}

# haze_id: what a cached reference depends on besides its scene: haze's
# version and the git tree of src/ (or the binary's hash outside git).
# BENCH_HAZE_ID overrides it, to keep the references of an earlier haze
# after a change shown not to alter images (tools/image-hashes.sh).
haze_id() {
    [ -z "${BENCH_HAZE_ID:-}" ] || { echo "$BENCH_HAZE_ID"; return; }
    v=$("$HAZE" --version 2>&1)
    t=$(git -C "$BENCH" rev-parse HEAD:src 2>/dev/null) || t=$(sha256sum <"$HAZE" | cut -c1-40)
    if [ -n "$(git -C "$BENCH" status --porcelain -- ../src 2>/dev/null)" ]; then
        t="$t-dirty-$(sha256sum <"$HAZE" | cut -c1-16)"
    fi
    echo "$v $t"
}

# key_of EXTRA FILE... -- WORDS: a hash of the files' contents, the words and
# EXTRA (when not empty).
key_of() {
    key_extra=$1
    shift
    {
        while [ $# -gt 0 ] && [ "$1" != -- ]; do cat "$1"; shift; done
        [ "$1" = -- ] && shift
        echo "$*"
        [ -z "$key_extra" ] || echo "$key_extra"
    } | sha256sum | cut -c1-16
}

# cache_key FILE... -- WORDS: for what haze renders, with haze_id.
cache_key() { key_of "$(haze_id)" "$@"; }

# content_key FILE... -- WORDS: without haze_id, for vdb_render's references,
# which survive changes to haze.
content_key() { key_of "" "$@"; }

# has_option NAME: haze render accepts --NAME (features being added on main).
has_option() { "$HAZE" --help 2>&1 | grep -q -e "--$1\b"; }

# has_estimator NAME: haze accepts "string transmittance" NAME.
has_estimator() {
    d=$CACHE/probe; mkdir -p "$d"
    cat >"$d/probe-$1.pbrt" <<EOF
Integrator "singlescatter" "string transmittance" "$1"
Camera "perspective"
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
EOF
    "$HAZE" render "$d/probe-$1.pbrt" --spp 1 --threads 1 -o "$d/probe.exr" --quiet >/dev/null 2>&1
}
