#!/usr/bin/env bash
# validate.sh - `make validate`: renders every scene with pdftrace (PFM: mean and variance of
# the mean per pixel) and with POV-Ray (+FE linear EXR, from the exported .pov), compares them
# with build/ptv and writes validation/out/index.html.
#   usage: validation/validate.sh PTV OUTDIR [SCENE...]
# Scenes whose reference is too slow for a routine run (the recipe's "high" radiosity) compare
# against scenes/ref/NAME.exr instead; `make validate-refs` remakes those (validate-refs.sh).
set -euo pipefail
ptv=$1 out=$2; shift 2
command -v povray >/dev/null || { echo "validate: povray is not installed (apt-get install povray)" >&2; exit 1; }
mkdir -p "$out"

# name            reference  size spp   bias_tol pov_err accept  note
table='
direct-quad       live       128  256   0.01     0.006   0.99    diffuse + quad light, direct only (16x16 spotlight grid; recipe 0.5 %)
direct-sphere     live       128  256   0.01     0.001   0.99    small bright sphere light = one fade-trick point light (recipe <= 0.05 %)
checker           live       128  256   0.01     0.002   0.99    checker texture, direct only (recipe: exact)
mirror            live       128  256   0.01     0.002   0.99    plane mirror, camera-mirror-diffuse + direct light (recipe: exact)
glass             live       128  256   0.01     0.002   0.99    glass ball seen through, exact Fresnel (recipe: exact)
mesh              live       128  256   0.01     0.006   0.99    OBJ mesh2 with vertex normals, direct only
cornell-diffuse   ref        128  1024  0.02     0.03    0       global illumination vs stored high-radiosity reference (scenes/ref; recipe -1 % mean, 1.5 % per pixel)
cornell           medium     128  1024  0.08     0.05    0       RTRL box with glass: loose, POV has no caustics without photons and medium radiosity is -3.8 % (recipe)
'
names=()
status=0
while read -r name ref size spp tol err acc note; do
    [ -n "$name" ] || continue
    if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
    names+=("$name")
    t0=$SECONDS
    "$ptv" render "scenes/$name.scene" "$out/$name.pfm" "$out/$name-var.pfm" "$size" "$size" "$spp"
    t1=$SECONDS
    if [ "$ref" = ref ]; then
        exr="scenes/ref/$name.exr"
        [ -f "$exr" ] || { echo "validate: $exr is missing: run make validate-refs" >&2; status=1; continue; }
        note="$note; reference: $exr"
    else
        exr="$out/$name.exr"
        if [ "$ref" = live ]; then "$ptv" pov "scenes/$name.scene" "$out/$name.pov" none "$size" "$size"
        else "$ptv" pov "scenes/$name.scene" "$out/$name.pov" "$ref" "$size" "$size"; fi
        rm -f "$exr"
        povray +I"$out/$name.pov" +O"$exr" +FE +W"$size" +H"$size" +A0.0 +AM2 +R4 -D -V -GA >"$out/$name-povray.log" 2>&1 ||
            { echo "validate: povray failed on $name, see $out/$name-povray.log" >&2; status=1; continue; }
        note="$note; POV-Ray live ($ref)"
    fi
    t2=$SECONDS
    "$ptv" compare "$name" "$out/$name.pfm" "$out/$name-var.pfm" "$exr" "$out" "$tol" "$err" "$acc" \
        "$note; pdftrace $((t1 - t0)) s, POV-Ray $((t2 - t1)) s" || status=1
done <<<"$table"
"$ptv" report "$out" "${names[@]}" || status=1
exit $status
