#!/bin/sh
# Regenerates the reference EXRs of tests/regression (make update-refs) and
# prints, for each scene, how the new reference differs from the old one, so a
# reviewer decides whether the change is intended before committing it.
#   usage: update-refs.sh HAZE [SCENE_NAME...]   (REF_SPP, default 4096; REF_SEED, default 0)
set -eu
haze=$1
shift
here=$(cd "$(dirname "$0")" && pwd)
spp=${REF_SPP:-4096}
seed=${REF_SEED:-0}
if [ $# -eq 0 ]; then
    set -- $(cd "$here/scenes" && ls *.pbrt | sed 's/\.pbrt$//')
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for name in "$@"; do
    scene="$here/scenes/$name.pbrt"
    ref="$here/refs/$name.exr"
    new="$tmp/$name.exr"
    [ -f "$scene" ] || { echo "update-refs: no scene $scene" >&2; exit 2; }
    start=$(date +%s)
    "$haze" render "$scene" --spp "$spp" --seed "$seed" --quiet -o "$new"
    echo "== $name: rendered at $spp spp in $(( $(date +%s) - start )) s"
    if [ -f "$ref" ]; then
        if cmp -s "$new" "$ref"; then
            echo "   unchanged (byte-identical)"
            continue
        fi
        echo "   changed; new vs old:"
        "$haze" diff "$new" "$ref" --channels R,G,B | sed 's/^/   /' || true
        "$haze" diff "$new" "$ref" --ztest | tail -n 1 | sed 's/^/   z-test new vs old: /' || true
    else
        echo "   new reference"
    fi
    cp "$new" "$ref"
done
echo "References in $here/refs; review with 'git diff --stat' and commit them with the change that caused them."
