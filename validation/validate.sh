#!/usr/bin/env bash
# validate.sh - `make validate`: renders every scene with pdftrace and compares it with POV-Ray
# (+FE linear EXR from the exported .pov) and with Mitsuba 3 (the exported XML rendered by
# validation/mitsuba_render.py), with build/ptv, and writes validation/out/index.html.
#   usage: validation/validate.sh PTV OUTDIR [--pov-only|--mitsuba-only] [SCENE...]
#   environment: PDFTRACE (build/pdftrace: the Mitsuba export), MITSUBA_PY (the Python of the
#   venv `make mitsuba-install` made; without it, or without the package, every Mitsuba row
#   prints SKIP and counts as skipped, never as passed)
# Scenes whose POV-Ray reference is too slow for a routine run (the recipe's "high" radiosity)
# compare against scenes/ref/NAME.exr instead; `make validate-refs` remakes those (validate-refs.sh).
set -euo pipefail
ptv=$1 out=$2; shift 2
mode=both
case "${1:-}" in --pov-only) mode=pov; shift;; --mitsuba-only) mode=mitsuba; shift;; esac
pdftrace=${PDFTRACE:-build/pdftrace}
mitsuba_py=${MITSUBA_PY:-build/mitsuba-venv/bin/python}
mkdir -p "$out"
status=0

# 1 when the scene is selected (no names given: every scene).
selected() { [ "$nsel" = 0 ] || [[ " $sel " == *" $1 "* ]]; }
nsel=$# sel="$*"

# ---- POV-Ray
# name            reference  size spp   bias_tol pov_err accept  note
pov_table='
direct-quad       live       128  256   0.01     0.006   0.99    diffuse + quad light, direct only (16x16 spotlight grid; recipe 0.5 %)
direct-sphere     live       128  256   0.01     0.001   0.99    small bright sphere light = one fade-trick point light (recipe <= 0.05 %)
checker           live       128  256   0.01     0.002   0.99    checker texture, direct only (recipe: exact)
mirror            live       128  256   0.01     0.002   0.99    plane mirror, camera-mirror-diffuse + direct light (recipe: exact)
glass             live       128  256   0.01     0.002   0.99    glass ball seen through, exact Fresnel (recipe: exact)
mesh              live       128  256   0.01     0.006   0.99    OBJ mesh2 with vertex normals, direct only
lights-direct     live       128  256   0.01     0.002   0.99    point, hard-cone spot and directional lights, direct only (recipe: exact)
cornell-diffuse   ref        128  1024  0.02     0.03    0       global illumination vs stored high-radiosity reference (scenes/ref; recipe -1 % mean, 1.5 % per pixel)
cornell           medium     128  1024  0.08     0.05    0       RTRL box with glass: loose, POV has no caustics without photons and medium radiosity is -3.8 % (recipe)
'
pov_names=()
run_pov() {
    local name=$1 ref=$2 size=$3 spp=$4 tol=$5 err=$6 acc=$7 note=$8 t0 t1 t2 exr
    t0=$SECONDS
    "$ptv" render "scenes/$name.scene" "$out/$name.pfm" "$out/$name-var.pfm" "$size" "$size" "$spp" || return 1
    t1=$SECONDS
    if [ "$ref" = ref ]; then
        exr="scenes/ref/$name.exr"
        [ -f "$exr" ] || { echo "validate: $exr is missing: run make validate-refs" >&2; return 1; }
        note="$note; reference: $exr"
    else
        exr="$out/$name.exr"
        if [ "$ref" = live ]; then "$ptv" pov "scenes/$name.scene" "$out/$name.pov" none "$size" "$size"
        else "$ptv" pov "scenes/$name.scene" "$out/$name.pov" "$ref" "$size" "$size"; fi
        rm -f "$exr"
        povray +I"$out/$name.pov" +O"$exr" +FE +W"$size" +H"$size" +A0.0 +AM2 +R4 -D -V -GA >"$out/$name-povray.log" 2>&1 ||
            { echo "validate: povray failed on $name, see $out/$name-povray.log" >&2; return 1; }
        note="$note; POV-Ray live ($ref)"
    fi
    t2=$SECONDS
    "$ptv" compare "$name" "$out/$name.pfm" "$out/$name-var.pfm" "$exr" "$out" "$tol" "$err" "$acc" \
        "$note; pdftrace $((t1 - t0)) s, POV-Ray $((t2 - t1)) s"
}
if [ "$mode" != mitsuba ]; then
    command -v povray >/dev/null || { echo "validate: povray is not installed (apt-get install povray)" >&2; exit 1; }
    while read -r name ref size spp tol err acc note; do
        [ -n "$name" ] && selected "$name" || continue
        pov_names+=("$name")
        run_pov "$name" "$ref" "$size" "$spp" "$tol" "$err" "$acc" "$note" || status=1
    done <<<"$pov_table"
fi

# ---- Mitsuba 3
# Every scene of scenes/ and bench/scenes/: size (square), seeds per renderer, samples per pixel
# and seed, and the test that decides besides the bias test (pixel: per-pixel Welch t on >= 99 %
# of pixels; region: 4x4 region means, for heavy-tailed caustic noise). Sample counts give the
# bias test a standard error of <= ~0.1 % (so a 0.5 % bias shows) in about a minute per scene.
# name            dir            size seeds spp   test    note
mi_table='
direct-quad       scenes         64   16    256   pixel   quad light, direct only
direct-sphere     scenes         64   16    256   pixel   small bright sphere light, direct only
checker           scenes         64   16    256   pixel   3-D checker texture
mirror            scenes         64   16    1024  pixel   plane mirror
glass             scenes         64   16    256   pixel   glass ball seen through, exact Fresnel
mesh              scenes         64   16    256   pixel   OBJ mesh with vertex normals
cornell-diffuse   scenes         64   16    512   pixel   global illumination
lights-direct     scenes         64   16    256   pixel   point, hard spot and directional lights, direct only
lights            scenes         64   16    512   pixel   point, soft spot and directional lights, indirect light
cornell           scenes         64   16    512   region  RTRL box: glass ball, caustics (heavy-tailed)
env               scenes         64   16    256   pixel   sky map with a sun (scale 0.5, rotated), a diffuse ball, a mirror ball in its shadow
rough-metal       scenes         64   16    256   pixel   GGX rough conductors (gold, copper, aluminium, silver) under a quad and a sphere light
rough-plastic     scenes         64   16    128   pixel   GGX-coated plastics (alpha 0.02 .. 0.6, one nonlinear) under a quad and a sphere light
rough-glass       scenes         64   16    256   pixel   GGX rough dielectrics (two balls, a pane seen through) under a quad and a sphere light
textured          scenes         64   16    256   pixel   image textures over (u, v): an image on a quad, a sphere and an OBJ with vt (repeat)
balls             bench/scenes   64   16    256   pixel   diffuse balls, global illumination
many-lights       bench/scenes   64   16    512   pixel   five lights over four orders of power
metal-glass       bench/scenes   64   16    512   region  mirror and glass balls, caustics (heavy-tailed)
sky               bench/scenes   64   16    256   pixel   uniform sky only, mirror ball
tiny-light        bench/scenes   64   16    512   pixel   tiny bright sphere light and a dim window
tiny-light-pure   bench/scenes   64   16    512   pixel   tiny bright sphere light only
door              bench/scenes   64   16    512   region  Veach door: light only through a gap (heavy-tailed)
caustic           bench/scenes   64   16    512   region  a glass ball caustic on a diffuse floor (heavy-tailed)
cornell-guided    scenes         64   16    512   region  RTRL box, pdftrace with path guiding on
door-guided       bench/scenes   64   16    512   region  Veach door, pdftrace with path guiding on
caustic-guided    bench/scenes   64   16    512   region  the caustic, pdftrace with path guiding on
'
# A row NAME-guided renders NAME's scene with path guiding on (ptv render with PTV_GUIDING=on);
# Mitsuba renders the same scene, so the row checks that guiding leaves the image unbiased.
# Scenes where Mitsuba 3.9 is known to be wrong, with the reason (docs/accuracy.md, "Tiny sphere
# lights and Mitsuba"). Such a row is KNOWN, not FAIL, only if pdftrace is darker than Mitsuba by
# at most 0.5 % in every channel (ptv report); pdftrace itself is checked there against the
# exact answer by make test's analytic.image_tiny_sphere_light.
mi_known_reason="Mitsuba 3.9 computes a sphere light's cone density in float, which makes a light as small as this one (r/d ~ 0.005) about 0.07 % too bright (docs/accuracy.md)"
mi_known=" tiny-light tiny-light-pure "
mi_names=()
mi_skip=""
if [ "$mode" != pov ]; then
    if [ ! -x "$mitsuba_py" ]; then mi_skip="no Mitsuba venv at $mitsuba_py (make mitsuba-install)"
    elif ! "$mitsuba_py" -c 'import mitsuba' 2>/dev/null; then mi_skip="$mitsuba_py cannot import mitsuba (make mitsuba-install)"
    fi
fi
# One Mitsuba row: export (a refusal is reported, not failed), both renders, the comparison.
run_mitsuba() {
    local name=$1 dir=$2 size=$3 seeds=$4 spp=$5 test=$6 note=$7 t0 t1 t2 msg guiding=off
    local xml="$out/mitsuba/$name.xml" res="$out/$name-mitsuba.result" scene=$1
    if [[ $name == *-guided ]]; then scene=${name%-guided}; guiding=on; fi
    rm -f "$res"
    if [ -n "$mi_skip" ]; then
        echo "SKIP $name (Mitsuba): $mi_skip"; echo "skip $mi_skip" >"$res"; return 0
    fi
    mkdir -p "$out/mitsuba"
    if ! "$pdftrace" "$dir/$scene.scene" --export-mitsuba "$xml" --size "${size}x$size" --spp "$spp" \
        >"$out/$name-export.log" 2>&1; then
        msg=$(tr '\n' ' ' <"$out/$name-export.log")
        if grep -q "$scene.scene" "$out/$name-export.log"; then # refused with file:line and the reason
            echo "NOT EXPORTED $name (Mitsuba): $msg"; echo "refused $msg" >"$res"; return 0
        fi
        echo "FAIL $name (Mitsuba): export failed: $msg" >&2; return 1
    fi
    t0=$SECONDS
    "$mitsuba_py" validation/mitsuba_render.py "$xml" "$out/$name-mi" "$seeds" "$spp" >"$out/$name-mitsuba.log" 2>&1 ||
        { echo "FAIL $name (Mitsuba): mitsuba_render failed: $(tail -n 3 "$out/$name-mitsuba.log")" >&2; return 1; }
    # Mitsuba's own warnings fail the render (its logger raises); drjit's go to stderr, so the log
    if grep -qi 'warn' "$out/$name-mitsuba.log"; then
        echo "FAIL $name (Mitsuba): warnings in $out/$name-mitsuba.log: $(grep -i -m 2 'warn' "$out/$name-mitsuba.log")" >&2
        return 1
    fi
    t1=$SECONDS
    PTV_GUIDING=$guiding "$ptv" render "$dir/$scene.scene" "$out/$name-ptm.pfm" "$out/$name-ptm-var.pfm" "$size" "$size" "$spp" "$seeds" \
        "$out/$name-ptm-regions.txt" || return 1
    t2=$SECONDS
    local rc=0
    "$ptv" compare-mitsuba "$name" "$out/$name-ptm" "$out/$name-mi" "$out" "$test" \
        "$note; $seeds seeds x $spp spp each; $(grep -o 'llvm_ad_rgb\|scalar_rgb' "$out/$name-mitsuba.log" | head -n 1);" \
        "Mitsuba $((t1 - t0)) s, pdftrace $((t2 - t1)) s" || rc=$?
    if [[ $mi_known == *" $name "* ]] && [ -s "$res" ]; then
        echo "known $mi_known_reason" >>"$res"
        [ "$rc" != 3 ] || rc=0 # a failed comparison: ptv report decides whether it is the known one
    fi
    return "$rc"
}
if [ "$mode" != pov ]; then
    while read -r name dir size seeds spp test note; do
        [ -n "$name" ] && selected "$name" || continue
        mi_names+=("$name")
        run_mitsuba "$name" "$dir" "$size" "$seeds" "$spp" "$test" "$note" || status=1
    done <<<"$mi_table"
fi

"$ptv" report "$out" ${pov_names[@]+"${pov_names[@]}"} --mitsuba ${mi_names[@]+"${mi_names[@]}"} || status=1
[ -z "$mi_skip" ] || echo "validate: the Mitsuba rows were SKIPPED: $mi_skip"
exit $status
