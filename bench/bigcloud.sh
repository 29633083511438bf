# make bench's bigcloud part (sourced by bench/run.sh): a production-sized
# cloud as pbrt-v4-scenes' disney-cloud renders one, haze against pbrt-v4 at
# equal error. cloud-250 (haze_scale_volumes: four blobs eroded by fBm noise,
# 500^3 voxels, 29M active, a 133 MiB .nvdb) under volpath maxdepth 100,
# albedo 1, g 0.877, optical depth about 60 across its core, a distant sun and
# a blue sky, 120x90. Both renderers are measured against one haze reference
# (1024 spp, cached per haze_id); pbrt-v4's mean against it says the two agree.
# Writes bigcloud.tsv and bigcloud.md.

BIGCLOUD_DIR=$CACHE/scale
BIGCLOUD_GEN=${HAZE_SCALE_VOLUMES:-$(dirname "$HAZE")/bench/haze_scale_volumes}
bigcloud_ref_spp=1024
bigcloud_rungs="16 64"

# bigcloud_scene OUT.pbrt NVDB
bigcloud_scene() {
    cat >"$1" <<EOF
Integrator "volpath" "integer maxdepth" 100
Sampler "zsobol" "integer pixelsamples" 16
Film "rgb" "integer xresolution" 120 "integer yresolution" 90 "string filename" "bigcloud.exr"
LookAt 0.6 0.5 -3.6   0 0.05 0   0 1 0
Camera "perspective" "float fov" 38
WorldBegin
LightSource "infinite" "rgb L" [0.03 0.07 0.23]
LightSource "distant" "point3 to" [-0.58 -0.77 0.27] "rgb L" [2.6 2.5 2.3]
MakeNamedMedium "cloud" "string type" "nanovdb" "string filename" "$2"
    "rgb sigma_a" [0 0 0] "rgb sigma_s" [1 1 1] "float g" 0.877 "float scale" 40
AttributeBegin
  Material "interface"
  MediumInterface "cloud" ""
  Shape "trianglemesh" "integer indices" [0 6 2  0 4 6  1 3 7  1 7 5  0 1 5  0 5 4  2 7 3  2 6 7  0 3 1  0 2 3  4 5 7  4 7 6]
      "point3 P" [-1.2 -1.2 -1.2  1.2 -1.2 -1.2  -1.2 1.2 -1.2  1.2 1.2 -1.2  -1.2 -1.2 1.2  1.2 -1.2 1.2  -1.2 1.2 1.2  1.2 1.2 1.2]
AttributeEnd
EOF
}

# bigcloud_row WHO SPP TIMING-FILE IMAGE REF: one row of bigcloud.tsv.
bigcloud_row() {
    e=$(errors "$4" "$5" | cut -d' ' -f2)
    mean=$("$HAZE" diff "$4" "$5" --channels R,G,B | awk '$1 == "all" { printf "%+.2f%%", 100 * $(NF - 2) }')
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$(cut -d' ' -f1 "$3")" "$(cut -d' ' -f2 "$3")" "$e" "$mean" >>"$RESULTS/bigcloud.tsv"
    echo "  $1 $2 spp: cpu $(cut -d' ' -f1 "$3") s, relMSE $e, mean $mean" >&2
}

bigcloud_run() {
    [ -x /usr/bin/time ] || { echo "bench: the bigcloud part needs GNU time (/usr/bin/time)" >&2; exit 1; }
    mkdir -p "$BIGCLOUD_DIR"
    # BENCH_QUICK: a 256-spp reference and one rung.
    [ -z "$BENCH_QUICK" ] || bigcloud_ref_spp=256 bigcloud_rungs=16
    nv=$BIGCLOUD_DIR/cloud-250.nvdb
    if [ ! -f "$nv" ]; then
        [ -x "$BIGCLOUD_GEN" ] || { echo "bench: $BIGCLOUD_GEN is not built (cmake --build build)" >&2; exit 1; }
        echo "  generating cloud 250" >&2
        "$BIGCLOUD_GEN" "$BIGCLOUD_DIR" cloud 250 >>"$LOG" 2>&1 || { echo "bench: haze_scale_volumes cloud 250 failed" >&2; exit 1; }
    fi
    scene=$BIGCLOUD_DIR/bigcloud.pbrt
    bigcloud_scene "$scene" "$nv"
    key=$(cache_key "$scene" "$nv" -- "bigcloud $bigcloud_ref_spp")
    ref=$BIGCLOUD_DIR/ref-bigcloud-$key.exr
    if [ ! -f "$ref" ]; then
        echo "  reference: $bigcloud_ref_spp spp (cached as $(basename "$ref"))" >&2
        "$HAZE" render "$scene" --spp "$bigcloud_ref_spp" --threads "$THREADS" --seed 99 -o "$ref.tmp.exr" --quiet >>"$LOG" 2>&1 ||
            { echo "bench: the bigcloud reference failed" >&2; exit 1; }
        mv "$ref.tmp.exr" "$ref"
    fi
    printf 'who\tspp\tcpu_s\twall_s\trelmse\tmean\n' >"$RESULTS/bigcloud.tsv"
    for n in $bigcloud_rungs; do
        cpu_timed "$BIGCLOUD_DIR/t" 1e30 "$HAZE" render "$scene" --spp "$n" --threads "$THREADS" --seed 1 -o "$BIGCLOUD_DIR/haze.exr" --quiet
        bigcloud_row haze "$n" "$BIGCLOUD_DIR/t" "$BIGCLOUD_DIR/haze.exr" "$ref"
        if [ -n "${PBRT:-}" ]; then
            cpu_timed "$BIGCLOUD_DIR/t" 1e30 "$PBRT" --quiet --nthreads "$THREADS" --spp "$n" --seed 1 --outfile "$BIGCLOUD_DIR/pbrt.exr" "$scene"
            bigcloud_row pbrt-v4 "$n" "$BIGCLOUD_DIR/t" "$BIGCLOUD_DIR/pbrt.exr" "$ref"
        fi
    done
    bigcloud_report
}

bigcloud_report() {
    t=$RESULTS/bigcloud.tsv
    {
        echo "# A production-sized cloud: haze against pbrt-v4 at equal error"
        echo
        echo "Written by \`make bench\` (the bigcloud part, bench/bigcloud.sh) on $(date -u '+%Y-%m-%d %H:%M') UTC,"
        echo "$THREADS threads, load average before the run $BENCH_LOAD, $(haze_id)."
        echo
        echo "The scene: cloud-250 (500^3 voxels, 29M active, a 133 MiB .nvdb; four blobs eroded by"
        echo "fBm noise), \`volpath\` maxdepth 100, sigma_s 40 x density, albedo 1, g 0.877 (the albedo,"
        echo "phase and depth of pbrt-v4-scenes' disney-cloud). 120x90; both renderers against one haze"
        echo "reference of $bigcloud_ref_spp spp. CPU = user + sys of the whole process (median of three)."
        echo
        echo "| renderer | spp | CPU s | wall s | relMSE | mean vs reference | CPU x relMSE |"
        echo "|---|---|---|---|---|---|---|"
        awk -F'\t' 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %.3g |\n", $1, $2, $3, $4, $5, $6, $3 * $5 }' "$t"
        echo
        awk -F'\t' 'NR > 1 { w[$1 " " $2] = $3 * $5; top = $2 }
            END {
                if (("pbrt-v4 " top) in w)
                    printf "haze / pbrt-v4 at equal error (CPU x relMSE at %s spp; relMSE falls as 1/spp): %.2f (target 0.5).\n", top, w["haze " top] / w["pbrt-v4 " top]
                else
                    print "pbrt-v4 not measured (PBRT unset)."
            }' "$t"
    } >"$RESULTS/bigcloud.md"
}
