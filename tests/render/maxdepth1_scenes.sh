#!/bin/sh
# Integrator "volpath" with maxdepth 1 is single scattering: on a scene of
# scenes/, at a fifth of its resolution, the image mean of volpath maxdepth 1
# (A) must match singlescatter with ratio tracking (B, unbiased, 4x the
# samples) within noise: `haze diff --ztest` at the image level (--accept 0
# lets pixel and block tests fail: volpath's one light sample per scattering
# event is heavy-tailed in thin fog under narrow spot lights, where 16 samples
# of a pixel often miss every cone and underestimate its variance; the image
# sums thousands of pixels). The scene's own Integrator line is replaced; the copy sits
# in a mirror of the repository (scenes/ beside a link to volumes/) so its
# relative paths still resolve. The Film writes its variance for the test.
#   usage: maxdepth1_scenes.sh HAZE REPO SCENE_NAME OUTDIR [SPP]
set -eu
haze=$1 repo=$2 name=$3 out=$4 spp=${5:-16}
mirror=$out/mirror
mkdir -p "$mirror/scenes"
[ -e "$mirror/volumes" ] || ln -s "$repo/volumes" "$mirror/volumes"
variant() { # variant INTEGRATOR-LINE OUT.pbrt
    { echo "$1"
      awk '/^Integrator/ { skip = 1; next }
           skip && /^[ \t]/ { next }
           { skip = 0
             sub(/^Film "rgb"/, "Film \"rgb\" \"bool writevariance\" true")
             for (i = 1; i < NF; i++)
                 if ($i == "\"integer" && ($(i + 1) == "xresolution\"" || $(i + 1) == "yresolution\""))
                     $(i + 2) = int($(i + 2) / 5)
             print }' "$repo/scenes/$name.pbrt"
    } >"$2"
}
a=$mirror/scenes/$name.volpath1.pbrt
b=$mirror/scenes/$name.single.pbrt
variant 'Integrator "volpath" "integer maxdepth" 1' "$a"
variant 'Integrator "singlescatter" "string transmittance" "ratio"' "$b"
if grep -q '^Integrator' "$repo/scenes/$name.pbrt" && [ "$(grep -c '^Integrator' "$a")" != 1 ]; then
    echo "$name: the scene's Integrator was not replaced" >&2; exit 1
fi
"$haze" render "$a" --spp "$spp" --seed 7 --quiet -o "$out/$name.volpath1.exr"
"$haze" render "$b" --spp $((4 * spp)) --seed 8 --quiet -o "$out/$name.single.exr"
"$haze" diff "$out/$name.volpath1.exr" "$out/$name.single.exr" --ztest --accept 0
