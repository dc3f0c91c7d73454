#!/usr/bin/env bash
# pdftrace.sh - tests of the pdftrace command (tools/pdftrace.c), run by `make test` and
# `make cli-test`:
#     tests/cli/pdftrace.sh build/pdftrace scenes WORKDIR
# Prints "PASS name (details)", "FAIL name: reason" or "SKIP name: reason" per test and as its
# last line "N passed, M failed, K skipped"; exit status 0 iff nothing failed.
# Checked: PNG and EXR files are valid (PNG signature and IHDR, the EXR magic number and, with
# exrheader, the data window); --help fits in 40 lines; bad options, values, scene files and
# outputs exit with status 2, one line on stderr and no file written; --export-pov;
# --export-mitsuba (alone, with -o, with the overrides, and a refused scene); the
# default output name; --preview-every rewrites the output while rendering and leaves the
# final image as without it; the command line overrides a scene file's settings; --exposure
# changes the 8-bit outputs only; -q prints nothing; --adaptive-mode and its alias; path guiding
# (--guiding*, the scene file's guiding statements, --guide-at's picture, exports unchanged by them);
# the environment statement (a map renders and exports, its errors name file:line).
set -u

if [ $# -ne 3 ]; then
    echo "usage: $0 PDFTRACE SCENEDIR WORKDIR" >&2
    exit 2
fi
abspath() { case $1 in /*) printf '%s\n' "$1" ;; *) printf '%s/%s\n' "$PWD" "$1" ;; esac; }
P=$(abspath "$1")
S=$(abspath "$2")
W=$(abspath "$3")
rm -rf "$W"
mkdir -p "$W" || exit 2

passed=0 failed=0 skipped=0
pass() { printf 'PASS cli.%s (%s)\n' "$1" "$2"; passed=$((passed + 1)); }
fail() { printf 'FAIL cli.%s: %s\n' "$1" "$2"; failed=$((failed + 1)); }
skip() { printf 'SKIP cli.%s: %s\n' "$1" "$2"; skipped=$((skipped + 1)); }

version=$("$P" --version 2>&1)
have_png=0 have_exr=0
case $version in *"PNG yes"*) have_png=1 ;; esac
case $version in *"OpenEXR yes"*) have_exr=1 ;; esac

# The bytes of a file from offset $2, $3 of them, as hex without spaces.
hexbytes() { od -An -tx1 -j "$2" -N "$3" "$1" | tr -d ' \n'; }

# ---- help and version
t_help() {
    local n status
    n=$("$P" --help | wc -l)
    "$P" -h >"$W/h.txt"
    status=$?
    if [ "$n" -le 40 ] && [ "$status" = 0 ] && "$P" --help | cmp -s - "$W/h.txt"; then
        pass help "--help is $n lines, -h is the same"
    else
        fail help "--help is $n lines (want <= 40), -h exit status $status or a different text"
    fi
    if [[ $version =~ ^pdftrace\ [0-9]+\.[0-9]+\.[0-9]+\  ]] && [ "$(printf '%s\n' "$version" | wc -l)" = 1 ]; then
        pass version "$version"
    else
        fail version "--version printed '$version'"
    fi
}

# ---- PNG and EXR outputs of a 600 x 600 scene
t_png_exr() {
    local dir=$W/formats args=() what=""
    mkdir -p "$dir"
    [ $have_png = 1 ] && args+=(-o "$dir/c.png") && what="png"
    [ $have_exr = 1 ] && args+=(-o "$dir/c.exr") && what="$what exr"
    if [ ${#args[@]} = 0 ]; then
        skip png_exr "built without libpng and OpenEXR"
        return
    fi
    if ! "$P" "$S/cornell.scene" -q --spp 1 "${args[@]}" -o "$dir/c.pfm" -o "$dir/c.ppm" 2>"$W/err.txt"; then
        fail png_exr "the render failed: $(head -n 1 "$W/err.txt")"
        return
    fi
    if [ $have_png = 1 ]; then
        # signature, then the IHDR chunk: length 13, "IHDR", width, height, depth 8, colour type 2 (RGB)
        local want=89504e470d0a1a0a0000000d49484452000002580000025808020000
        local got
        got=$(hexbytes "$dir/c.png" 0 28)
        [ "$got" = "$want" ] || { fail png_exr "c.png starts with $got, want $want (600 x 600 8-bit RGB)"; return; }
    fi
    if [ $have_exr = 1 ]; then
        [ "$(hexbytes "$dir/c.exr" 0 4)" = 762f3101 ] || { fail png_exr "c.exr has no OpenEXR magic number"; return; }
        if command -v exrheader >/dev/null; then
            exrheader "$dir/c.exr" | grep -q 'dataWindow (type box2i): (0 0) - (599 599)' ||
                { fail png_exr "exrheader: c.exr's data window is not (0 0) - (599 599)"; return; }
            what="$what (exrheader)"
        fi
    fi
    [ "$(head -c 15 "$dir/c.ppm" | tr '\n' ' ')" = "P6 600 600 255 " ] || { fail png_exr "c.ppm header"; return; }
    [ "$(head -c 14 "$dir/c.pfm" | tr '\n' ' ')" = "PF 600 600 -1." ] || { fail png_exr "c.pfm header"; return; }
    [ -z "$(ls "$dir" | grep -v '^c\.\(png\|exr\|pfm\|ppm\)$')" ] || { fail png_exr "extra files: $(ls "$dir")"; return; }
    pass png_exr "$what ppm pfm: 600x600 headers"
}

# ---- bad input: status 2, one line "pdftrace: ..." on stderr, nothing written
bad_case() { # what, arguments...
    local what=$1 status lines first
    shift
    rm -rf "$W/bad" && mkdir -p "$W/bad"
    (cd "$W/bad" && "$P" "$@" >"$W/out.txt" 2>"$W/err.txt")
    status=$?
    lines=$(wc -l <"$W/err.txt")
    first=$(head -n 1 "$W/err.txt")
    if [ "$status" != 2 ] || [ "$lines" != 1 ] || [[ $first != pdftrace:\ * ]] || [ -n "$(ls -A "$W/bad")" ]; then
        fail "bad_input" "$what: status $status, $lines stderr lines ('$first'), files: $(ls -A "$W/bad" | tr '\n' ' ')"
        return 1
    fi
    printf '    %-34s -> %s\n' "$what" "$first"
    return 0
}
t_bad_input() {
    local ok=1 a
    printf 'size 8 8\ncamera look_from 0 0 -5 look_at 0 0 0\nbogus 1 2 3\n' >"$W/broken.scene"
    for a in "--bogus" "--spp 0" "--spp abc" "--width -5" "--size 3x" "--strategy best" "--sampler halton" \
             "--light-weight 2" "--threads" "--tonemap filmic" "--exposure inf" "--preview-every 0" "--adaptive -1" \
             "--adaptive-mode best" \
             "--disable-skips nope" "--indirect-paths 9" "--backend fast" "--integrator fast" "--quiet=1" "-o out.tiff" \
             "-o no/such/dir/x.ppm" "--export-pov no/such/dir/x.pov" "--export-mitsuba no/such/dir/x.xml" \
             "--guiding sometimes" "--guiding" "--guiding-budget 1.5" "--guiding-budget 0" "--guiding-budget 1" \
             "--guiding-alpha 0" "--guiding-alpha nan" "--guiding-memory 0" "--guiding-memory 2.5" \
             "--guide-at 0 0 nan g.pfm" "--guide-at 0 inf 0 g.pfm" "--guide-at 1e39 0 0 g.pfm" "--guide-at x 0 0 g.pfm" \
             "--guide-at 0 0 0 g.tiff" "--guide-at 0 0 0" "--guide-at 0 0 0 no/such/dir/g.pfm" \
             "--guiding off --guide-at 0 0 0 g.pfm" "--guide-at 0 0 0 g.pfm --guide-at 0 0 0 h.pfm"; do
        # shellcheck disable=SC2086
        bad_case "$a" "$S/mirror.scene" --spp 1 --size 8x8 -o "$W/bad/x.ppm" $a || ok=0
    done
    bad_case "missing scene file" "$S/no-such.scene" -o "$W/bad/x.ppm" || ok=0
    bad_case "unparseable scene file" "$W/broken.scene" -o "$W/bad/x.ppm" || ok=0
    grep -q "broken.scene:3: " "$W/err.txt" || { fail bad_input "no file:line in '$(cat "$W/err.txt")'"; ok=0; }
    bad_case "no scene file" -o "$W/bad/x.ppm" || ok=0
    bad_case "two scene files" "$S/mirror.scene" "$S/glass.scene" || ok=0
    case $version in
    *"Embree no"*) bad_case "--backend embree (no Embree)" "$S/mirror.scene" --backend embree -o "$W/bad/x.ppm" || ok=0 ;;
    esac
    if [ $have_png = 0 ]; then
        bad_case "-o x.png (no libpng)" "$S/mirror.scene" -o "$W/bad/x.png" || ok=0
        grep -q "x.png: built without PNG support (install libpng-dev and rebuild)" "$W/err.txt" ||
            { fail bad_input "-o x.png without libpng: '$(cat "$W/err.txt")'"; ok=0; }
    fi
    if [ $have_exr = 0 ]; then
        bad_case "-o x.exr (no OpenEXR)" "$S/mirror.scene" -o "$W/bad/x.exr" || ok=0
    fi
    [ $ok = 1 ] && pass bad_input "status 2, one line, no file, for each case above"
}

# ---- --export-pov: alone it writes only the .pov; with -o it renders too
t_export_pov() {
    local dir=$W/pov status
    mkdir -p "$dir"
    if ! (cd "$dir" && "$P" "$S/mirror.scene" -q --export-pov m.pov) 2>"$W/err.txt"; then
        fail export_pov "failed: $(head -n 1 "$W/err.txt")"
        return
    fi
    if [ "$(ls "$dir")" != m.pov ] || ! grep -q '^camera' "$dir/m.pov"; then
        fail export_pov "wrote '$(ls "$dir" | tr '\n' ' ')' (want only m.pov, with a camera)"
        return
    fi
    rm -f "$dir/m.pov"
    if ! "$P" "$S/mirror.scene" -q --spp 1 --size 16x16 --export-pov "$dir/m.pov" -o "$dir/m.pfm" 2>"$W/err.txt" ||
        [ ! -s "$dir/m.pov" ] || [ ! -s "$dir/m.pfm" ]; then
        fail export_pov "with -o: $(head -n 1 "$W/err.txt"); wrote $(ls "$dir" | tr '\n' ' ')"
        return
    fi
    rm -f "$dir"/*
    # a soft-edged spot light has no POV-Ray twin: status 2, its file:line, nothing written
    "$P" "$S/lights.scene" -q --export-pov "$dir/l.pov" 2>"$W/err.txt"
    status=$?
    if [ $status != 2 ] || [ "$(wc -l <"$W/err.txt")" != 1 ] ||
        [[ $(head -n 1 "$W/err.txt") != *"lights.scene:25: POV-Ray export: a spot light with a beam of 12 degrees"* ]] ||
        [ -n "$(ls -A "$dir")" ]; then
        fail export_pov "lights.scene: status $status, '$(head -n 1 "$W/err.txt")', files: $(ls -A "$dir" | tr '\n' ' ')"
        return
    fi
    pass export_pov "alone: only the .pov; with -o: the .pov and the image; a soft spot light refused"
}

# ---- --export-mitsuba: alone it writes the .xml and its PLY files only, with the command
# line's size, spp and depth (written as depth + 1); with -o it renders too; a scene Mitsuba has
# no exact twin for is refused (status 2, file:line, no file)
t_export_mitsuba() {
    local dir=$W/mitsuba first lines status
    mkdir -p "$dir"
    if ! (cd "$dir" && "$P" "$S/mesh.scene" -q --size 20x10 --spp 3 --max-depth 4 --export-mitsuba m.xml) 2>"$W/err.txt"; then
        fail export_mitsuba "failed: $(head -n 1 "$W/err.txt")"
        return
    fi
    if [ "$(ls "$dir" | tr '\n' ' ')" != "m.0.ply m.xml " ] ||
        ! grep -q '<integer name="width" value="20"/><integer name="height" value="10"/>' "$dir/m.xml" ||
        ! grep -q '<integer name="sample_count" value="3"/>' "$dir/m.xml" ||
        ! grep -q '<integer name="max_depth" value="5"/>' "$dir/m.xml" ||
        [ "$(head -c 36 "$dir/m.0.ply")" != "$(printf 'ply\nformat binary_little_endian 1.0')" ]; then
        fail export_mitsuba "wrote '$(ls "$dir" | tr '\n' ' ')' (want m.0.ply m.xml, 20x10, spp 3, max_depth 5)"
        return
    fi
    rm -f "$dir"/*
    if ! "$P" "$S/mirror.scene" -q --spp 1 --size 16x16 --export-mitsuba "$dir/m.xml" -o "$dir/m.pfm" 2>"$W/err.txt" ||
        [ ! -s "$dir/m.xml" ] || [ ! -s "$dir/m.pfm" ]; then
        fail export_mitsuba "with -o: $(head -n 1 "$W/err.txt"); wrote $(ls "$dir" | tr '\n' ' ')"
        return
    fi
    rm -f "$dir"/*
    "$P" "$S/checker.scene" -q --export-mitsuba "$dir/c.xml" 2>"$W/err.txt"
    status=$?
    lines=$(wc -l <"$W/err.txt")
    first=$(head -n 1 "$W/err.txt")
    if [ $status != 2 ] || [ "$lines" != 1 ] || [[ $first != *"checker.scene:16: Mitsuba export: the 3-D checker"* ]] ||
        [ -n "$(ls -A "$dir")" ]; then
        fail export_mitsuba "checker.scene: status $status, $lines lines ('$first'), files: $(ls -A "$dir" | tr '\n' ' ')"
        return
    fi
    pass export_mitsuba "alone: the .xml and its .ply, overrides applied; with -o: the image too; checker refused"
}

# ---- no -o: SCENE's base name in the current directory
t_default_output() {
    local dir=$W/default want=mirror.png
    [ $have_png = 1 ] || want=mirror.ppm
    mkdir -p "$dir"
    if (cd "$dir" && "$P" "$S/mirror.scene" -q --spp 1 --size 8x8) && [ "$(ls "$dir")" = "$want" ]; then
        pass default_output "$want"
    else
        fail default_output "wrote '$(ls "$dir" | tr '\n' ' ')', want $want"
    fi
}

# ---- --preview-every: the output appears and changes while the render runs
t_preview() {
    local dir=$W/preview out pid first="" sum changed=0 i running=1
    mkdir -p "$dir"
    out=$dir/p.pfm
    "$P" "$S/mirror.scene" -q --size 32x32 --spp 65536 --preview-every 0.05 -o "$out" 2>"$W/err.txt" &
    pid=$!
    for i in $(seq 1 1200); do # up to 60 s
        kill -0 "$pid" 2>/dev/null || { running=0; break; }
        if [ -f "$out" ]; then
            sum=$(cksum <"$out")
            if [ -z "$first" ]; then first=$sum; elif [ "$sum" != "$first" ]; then changed=1; break; fi
        fi
        sleep 0.05
    done
    kill "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    if [ $changed = 1 ]; then
        pass preview_every "the output was rewritten with new content while rendering (${i}th poll)"
    else
        fail preview_every "no change seen while running (running=$running, file $([ -f "$out" ] && echo present || echo absent))"
    fi
    # previews do not change the result, and leave no temporary files
    rm -rf "$dir" && mkdir -p "$dir"
    "$P" "$S/mirror.scene" -q --size 24x24 --spp 64 -o "$dir/a.pfm" &&
        "$P" "$S/mirror.scene" -q --size 24x24 --spp 64 --preview-every 0.000001 -o "$dir/b.pfm"
    if cmp -s "$dir/a.pfm" "$dir/b.pfm" && [ "$(ls "$dir" | wc -l)" = 2 ]; then
        pass preview_final "with previews after every pass the final image is the same bytes; no temporaries"
    else
        fail preview_final "the final image differs with --preview-every, or files are left: $(ls "$dir" | tr '\n' ' ')"
    fi
}

# ---- the command line over the scene file's settings
t_overrides() {
    local dir=$W/over ok=1 why=""
    mkdir -p "$dir"
    "$P" "$S/mirror.scene" -q --spp 1 --size 40x30 -o "$dir/size.pfm" &&
        "$P" "$S/mirror.scene" -q --spp 1 --width 24 -o "$dir/width.pfm" &&
        "$P" "$S/mirror.scene" -q --spp 2 --size 16x16 -o "$dir/spp2.pfm" &&
        "$P" "$S/mirror.scene" -q --spp 4 --size 16x16 -o "$dir/spp4.pfm" &&
        "$P" "$S/mirror.scene" -q --spp 2 --size 16x16 --seed 7 -o "$dir/seed7.pfm" &&
        "$P" "$S/mirror.scene" -q --spp 2 --size 16x16 --max-depth 1 -o "$dir/depth1.pfm" || { ok=0; why="a render failed"; }
    if [ $ok = 1 ]; then
        [ "$(head -c 8 "$dir/size.pfm" | tr '\n' ' ')" = "PF 40 30" ] || { ok=0; why="--size 40x30 not applied"; }
        [ "$(head -c 10 "$dir/width.pfm" | tr '\n' ' ')" = "PF 24 128 " ] || { ok=0; why="--width 24 did not keep the file's height 128"; }
        ! cmp -s "$dir/spp2.pfm" "$dir/spp4.pfm" || { ok=0; why="--spp had no effect"; }
        ! cmp -s "$dir/spp2.pfm" "$dir/seed7.pfm" || { ok=0; why="--seed had no effect"; }
        ! cmp -s "$dir/spp2.pfm" "$dir/depth1.pfm" || { ok=0; why="--max-depth had no effect"; }
    fi
    if [ $ok = 1 ]; then pass overrides "--size, --width (height from the file), --spp, --seed, --max-depth"
    else fail overrides "$why"; fi
}

# ---- --adaptive-mode: pilot is the default, own-samples and neighbours differ from it,
# --adaptive-neighbours-only is --adaptive-mode neighbours
t_adaptive_mode() {
    local dir=$W/adaptive ok=1 why="" m
    mkdir -p "$dir"
    for m in default pilot own-samples neighbours nb-flag; do
        case $m in
        default) set -- ;;
        nb-flag) set -- --adaptive-neighbours-only ;;
        *) set -- --adaptive-mode "$m" ;;
        esac
        "$P" "$S/glass.scene" -q --spp 64 --size 24x24 --adaptive 0.1 "$@" -o "$dir/$m.pfm" || { ok=0; why="$m: the render failed"; }
    done
    if [ $ok = 1 ]; then
        cmp -s "$dir/default.pfm" "$dir/pilot.pfm" || { ok=0; why="the default is not --adaptive-mode pilot"; }
        ! cmp -s "$dir/pilot.pfm" "$dir/own-samples.pfm" || { ok=0; why="own-samples is the pilot's image"; }
        ! cmp -s "$dir/own-samples.pfm" "$dir/neighbours.pfm" || { ok=0; why="neighbours is own-samples' image"; }
        cmp -s "$dir/neighbours.pfm" "$dir/nb-flag.pfm" || { ok=0; why="--adaptive-neighbours-only is not --adaptive-mode neighbours"; }
    fi
    if [ $ok = 1 ]; then pass adaptive_mode "default = pilot; own-samples, neighbours differ; --adaptive-neighbours-only = neighbours"
    else fail adaptive_mode "$why"; fi
}

# ---- --exposure and --tonemap change the 8-bit outputs, not the float ones; -q prints nothing
t_display() {
    local dir=$W/display
    mkdir -p "$dir"
    "$P" "$S/mirror.scene" -q --spp 2 --size 16x16 -o "$dir/a.ppm" -o "$dir/a.pfm" >"$W/out.txt" 2>&1 &&
        "$P" "$S/mirror.scene" -q --spp 2 --size 16x16 --exposure 1 --tonemap aces -o "$dir/b.ppm" -o "$dir/b.pfm" ||
        { fail display "a render failed"; return; }
    if [ -s "$W/out.txt" ]; then fail quiet "-q printed: $(head -n 1 "$W/out.txt")"; else pass quiet "no output"; fi
    if cmp -s "$dir/a.pfm" "$dir/b.pfm" && ! cmp -s "$dir/a.ppm" "$dir/b.ppm"; then
        pass display "--exposure 1 --tonemap aces: PPM changed, PFM the same bytes"
    else
        fail display "the PFM changed or the PPM did not"
    fi
}

# ---- what a scene file may do: read regular files inside its directory (or --allow-path),
# within --mesh-memory and --image-memory; its errors name file:line and echo no control bytes
t_scene_limits() {
    local d=$W/limits ok=1 head='camera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n' status
    mkdir -p "$d/scene" "$d/shared"
    printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$d/shared/t.obj"
    cp "$d/shared/t.obj" "$d/scene/t.obj"
    # a bad background is a load error with file:line (it loaded and failed later)
    printf "${head}background 1 1 nan\nsphere 0 0 0 1 m\n" >"$d/scene/nan.scene"
    bad_case "background 1 1 nan" "$d/scene/nan.scene" -o "$W/bad/x.ppm" || ok=0
    grep -q "nan.scene:3: background:" "$W/err.txt" || { fail scene_limits "background: '$(cat "$W/err.txt")'"; ok=0; }
    # meshes outside the scene's directory are refused unless allowed
    printf "${head}mesh ../shared/t.obj m\n" >"$d/scene/out.scene"
    bad_case "mesh ../shared/t.obj" "$d/scene/out.scene" -o "$W/bad/x.ppm" || ok=0
    grep -q "out.scene:3: mesh: no file '../shared/t.obj' inside the scene's directory" "$W/err.txt" ||
        { fail scene_limits "../shared: '$(cat "$W/err.txt")'"; ok=0; }
    "$P" "$d/scene/out.scene" -q --spp 1 --size 8x8 --allow-path "$d/shared" -o "$d/out.pfm" 2>"$W/err.txt" ||
        { fail scene_limits "--allow-path: $(cat "$W/err.txt")"; ok=0; }
    printf "${head}mesh /etc/shadow m\n" >"$d/scene/shadow.scene"
    bad_case "mesh /etc/shadow" "$d/scene/shadow.scene" -o "$W/bad/x.ppm" || ok=0
    ! grep -q "root" "$W/err.txt" || { fail scene_limits "/etc/shadow: '$(cat "$W/err.txt")'"; ok=0; }
    # a FIFO as the scene or as a mesh: refused at once (it blocked in fopen)
    if mkfifo "$d/scene/pipe.obj" "$d/pipe.scene" 2>/dev/null; then
        printf "${head}mesh pipe.obj m\n" >"$d/scene/fifo.scene"
        timeout 20 "$P" "$d/pipe.scene" -o "$d/x.ppm" 2>"$W/err.txt"
        status=$?
        [ $status = 2 ] && grep -q "pipe.scene: cannot read the scene: not a regular file" "$W/err.txt" ||
            { fail scene_limits "FIFO scene: status $status (124: it blocked), '$(cat "$W/err.txt")'"; ok=0; }
        timeout 20 "$P" "$d/scene/fifo.scene" -o "$d/x.ppm" 2>"$W/err.txt"
        status=$?
        [ $status = 2 ] && grep -q "fifo.scene:3: mesh: cannot read 'pipe.obj': not a regular file" "$W/err.txt" ||
            { fail scene_limits "FIFO mesh: status $status (124: it blocked), '$(cat "$W/err.txt")'"; ok=0; }
    else
        skip fifo "mkfifo failed"
    fi
    # the mesh memory budget: a 1.3 MB OBJ in 1 MiB
    awk 'BEGIN { for (i = 0; i < 30000; i++) printf "v %d 0 0\nv %d 1 0\nv %d 0 1\n", i, i, i;
                 for (i = 0; i < 30000; i++) printf "f %d %d %d\n", 3 * i + 1, 3 * i + 2, 3 * i + 3 }' >"$d/scene/big.obj"
    printf "${head}mesh t.obj m\nmesh big.obj m\n" >"$d/scene/big.scene"
    bad_case "--mesh-memory 1" "$d/scene/big.scene" --mesh-memory 1 -o "$W/bad/x.ppm" || ok=0
    grep -q "big.scene:4: mesh: 'big.obj' does not fit in the mesh memory budget of 1048576 bytes" "$W/err.txt" ||
        { fail scene_limits "--mesh-memory: '$(cat "$W/err.txt")'"; ok=0; }
    # size 16384 16384: refused at its line with the bytes it needs, before any allocation (run
    # under a 2 GB address-space limit and a timeout, so that a regression fails quickly)
    printf "size 16384 16384\n${head}sphere 0 0 0 1 m\n" >"$d/scene/huge.scene"
    printf '#!/bin/sh\nulimit -v 2097152\nexec timeout 60 "%s" "$@"\n' "$P" >"$d/limited.sh"
    chmod +x "$d/limited.sh"
    local P_saved=$P
    P=$d/limited.sh
    bad_case "size 16384 16384" "$d/scene/huge.scene" -o "$W/bad/x.ppm" || ok=0
    grep -q "huge.scene:1: size: a 16384 x 16384 render needs 46170898432 bytes" "$W/err.txt" ||
        { fail scene_limits "size: '$(cat "$W/err.txt")'"; ok=0; }
    bad_case "--size 16384x16384" "$S/mirror.scene" --size 16384x16384 -o "$W/bad/x.ppm" || ok=0
    P=$P_saved
    # an escape sequence in a scene line is printed escaped
    printf "${head}sph\033[2Jere 0 0 0 1 m\n" >"$d/scene/esc.scene"
    bad_case "ESC in a statement" "$d/scene/esc.scene" -o "$W/bad/x.ppm" || ok=0
    if grep -q "$(printf '\033')" "$W/err.txt" || ! grep -qF 'sph\x1b[2Jere' "$W/err.txt"; then
        fail scene_limits "ESC echoed raw: '$(cat -v "$W/err.txt")'"
        ok=0
    fi
    [ $ok = 1 ] && pass scene_limits "background, paths outside, --allow-path, /etc/shadow, FIFOs, --mesh-memory, size, escapes"
}

# ---- SIGINT or SIGTERM while an output is being written leaves no temporary file. The command
# is stopped (SIGSTOP) as soon as a temporary is seen; if it is still there, the signal is sent.
# Job control (set -m) keeps SIGINT of the background job from being ignored.
# 1 if this shell was started with signal $1 ignored (its SigIgn mask in /proc, Linux): a shell
# cannot undo an ignored signal it inherited, so its jobs ignore that signal too (a CI script
# started as `cmd &` from a shell without job control ignores SIGINT).
inherited_ignore() {
    local m
    m=$(sed -n 's/^SigIgn:[[:space:]]*//p' /proc/$$/status 2>/dev/null)
    [ -n "$m" ] && [ $(( (16#$m >> ($(kill -l "$1") - 1)) & 1 )) = 1 ]
}

t_signal() {
    local dir=$W/signal sig pid f caught i status left
    for sig in INT TERM; do
        if inherited_ignore "$sig"; then
            skip "signal_$sig" "SIG$sig is ignored in this shell's environment (inherited), so the command ignores it too"
            continue
        fi
        rm -rf "$dir" && mkdir -p "$dir"
        # 16 passes of 2 spp, each followed by a preview: a 7.7 MB PFM written through a temporary
        set -m
        "$P" "$S/mirror.scene" -q --size 800x800 --spp 32 --preview-every 0.01 -o "$dir/big.pfm" 2>/dev/null &
        pid=$!
        set +m
        caught=""
        for i in $(seq 1 1000000); do # busy-poll (no fork) for a temporary while the command runs
            for f in "$dir"/*.ptmp; do [ -e "$f" ] && caught=$f; done
            if [ -n "$caught" ]; then
                kill -STOP "$pid"
                [ -e "$caught" ] && break
                caught=""
                kill -CONT "$pid"
            fi
            kill -0 "$pid" 2>/dev/null || break
        done
        if [ -n "$caught" ]; then kill -"$sig" "$pid"; kill -CONT "$pid"; else kill "$pid" 2>/dev/null; fi
        wait "$pid" 2>/dev/null
        status=$?
        left=$(cd "$dir" && ls -- *.ptmp 2>/dev/null | tr '\n' ' ')
        if [ -z "$caught" ]; then
            skip "signal_$sig" "no temporary seen while the command ran"
        elif [ -n "$left" ]; then
            fail "signal_$sig" "SIG$sig while writing left $left($(du -k "$dir" | cut -f1) KB in the directory)"
        elif [ "$status" != $((128 + $(kill -l "$sig"))) ]; then
            fail "signal_$sig" "exit status $status, want $((128 + $(kill -l "$sig"))) (killed by SIG$sig)"
        else
            pass "signal_$sig" "SIG$sig while $(basename "$caught") was written: removed, exit status $status"
        fi
    done
}

# ---- an output that is the scene file (or a link to it) is refused, the scene kept
t_output_is_input() {
    local dir=$W/same ok=1 why="" status
    mkdir -p "$dir"
    cp "$S/mirror.scene" "$dir/s.pfm" && cp "$S/mirror.scene" "$dir/s.scene" && ln -s s.scene "$dir/link.ppm"
    "$P" "$dir/s.pfm" -q --size 8x8 --spp 1 -o "$dir/s.pfm" 2>"$W/err.txt"
    status=$?
    if [ $status != 2 ] || ! cmp -s "$S/mirror.scene" "$dir/s.pfm" || ! grep -q "scene file" "$W/err.txt"; then
        ok=0; why="-o SCENE: exit $status, $(head -n 1 "$W/err.txt")"
    fi
    "$P" "$dir/s.scene" -q --size 8x8 --spp 1 --export-pov "$dir/s.scene" 2>"$W/err.txt"
    status=$?
    if [ $status != 2 ] || ! cmp -s "$S/mirror.scene" "$dir/s.scene"; then
        ok=0; why="$why; --export-pov SCENE: exit $status, $(head -n 1 "$W/err.txt")"
    fi
    "$P" "$dir/s.scene" -q --size 8x8 --spp 1 -o "$dir/link.ppm" 2>"$W/err.txt"
    status=$?
    if [ $status != 2 ] || [ ! -L "$dir/link.ppm" ]; then ok=0; why="$why; -o LINK-TO-SCENE: exit $status"; fi
    if [ $ok = 1 ]; then pass output_is_input "-o SCENE, --export-pov SCENE, -o a link to it: exit 2, scene kept"
    else fail output_is_input "$why"; fi
}

# ---- a full disk (ulimit -f 1, SIGXFSZ ignored: writes fail with EFBIG): every output's message
# names its path, its temporary and the reason; nothing is left behind
t_disk_full() {
    local dir=$W/full args=() f ok=1 why="" reason="File too large" exts="pfm ppm" left
    mkdir -p "$dir"
    args=(-o "$dir/x.pfm" -o "$dir/x.ppm")
    [ $have_png = 1 ] && { args+=(-o "$dir/x.png"); exts="$exts png"; }
    [ $have_exr = 1 ] && { args+=(-o "$dir/x.exr"); exts="$exts exr"; }
    (trap '' XFSZ; ulimit -f 1; exec "$P" "$S/mirror.scene" -q --size 128x128 --spp 1 "${args[@]}") 2>"$W/err.txt"
    (trap '' XFSZ; ulimit -f 1; exec "$P" "$S/mirror.scene" -q --size 300x300 --export-pov "$dir/x.pov") 2>>"$W/err.txt"
    for f in "$dir"/*; do [ -e "$f" ] && { ok=0; why="$why $(basename "$f") left;"; }; done
    for f in $exts pov; do
        grep -q "^pdftrace: $dir/x.$f: .*'$dir/x.$f.[0-9a-f]*.ptmp'.*: $reason" "$W/err.txt" ||
            { ok=0; why="$why x.$f: no message with the path, the temporary and '$reason';"; }
    done
    if [ $ok = 1 ]; then pass disk_full "$(wc -l <"$W/err.txt") messages, e.g. $(head -n 1 "$W/err.txt")"
    else fail disk_full "$why ($(tr '\n' '|' <"$W/err.txt"))"; fi
}

# ---- a box 10 wide 4e6 from the centre of a floor 1e7 wide: below the spawn offset there, so the
# command warns on stderr (and renders); the same box without the floor is moved near the origin
t_precision_warning() {
    local dir=$W/precision f
    mkdir -p "$dir"
    for f in floor alone; do
        { printf 'size 8 8\nspp 1\ncamera look_from 4000005 5 3999900 look_at 4000005 5 4000005\n'
          printf 'material white lambertian 0.7 0.7 0.7\n'
          [ $f = floor ] && printf 'quad -5000000 0 -5000000 0 0 10000000 10000000 0 0 white\n'
          printf 'box 4000000 0 4000000 4000010 10 4000010 white\n'; } >"$dir/$f.scene"
        "$P" "$dir/$f.scene" -q -o "$dir/$f.pfm" 2>"$dir/$f.err" || { fail precision_warning "$f: render failed"; return; }
    done
    if grep -q "warning: .*floor.scene: 6 primitives too small for float" "$dir/floor.err" && [ ! -s "$dir/alone.err" ]; then
        pass precision_warning "far box on a huge floor: warned; alone: silent"
    else
        fail precision_warning "floor: '$(head -n 1 "$dir/floor.err")'; alone: '$(head -n 1 "$dir/alone.err")'"
    fi
}

# ---- path guiding: the scene file's guiding statements are the command line's --guiding options
# (same bytes), the command line overrides them, and they change the image; --guide-at writes the
# guide's 512 x 256 picture (alone: only it), turning guiding on; the exports ignore the statements
t_guiding() {
    local dir=$W/guiding ok=1 why="" f common=(-q --size 24x24 --spp 16) status
    mkdir -p "$dir/plain" "$dir/with"
    cp "$S/cornell.scene" "$dir/plain/c.scene"
    { cat "$S/cornell.scene"; printf '\nguiding on\n'; } >"$dir/on.scene"
    { cat "$S/cornell.scene"; printf '\nguiding off\n'; } >"$dir/off.scene"
    { cat "$S/cornell.scene"; printf '\nguiding on\nguiding_budget 0.5\nguiding_alpha 0.3\nguiding_memory 2\n'; } >"$dir/with/c.scene"
    "$P" "$dir/on.scene" "${common[@]}" -o "$dir/file-on.pfm" &&
        "$P" "$S/cornell.scene" "${common[@]}" --guiding on -o "$dir/cli-on.pfm" &&
        "$P" "$dir/on.scene" "${common[@]}" --guiding off -o "$dir/file-on-cli-off.pfm" &&
        "$P" "$S/cornell.scene" "${common[@]}" --guiding off -o "$dir/cli-off.pfm" &&
        "$P" "$dir/with/c.scene" "${common[@]}" -o "$dir/file-params.pfm" &&
        "$P" "$S/cornell.scene" "${common[@]}" --guiding=on --guiding-budget 0.5 --guiding-alpha=0.3 --guiding-memory 2 \
            -o "$dir/cli-params.pfm" &&
        "$P" "$S/cornell.scene" "${common[@]}" --guiding auto -o "$dir/cli-auto.pfm" ||
        { ok=0; why="a render failed"; }
    if [ $ok = 1 ]; then
        cmp -s "$dir/file-on.pfm" "$dir/cli-on.pfm" || { ok=0; why="'guiding on' in the file != --guiding on"; }
        cmp -s "$dir/file-on-cli-off.pfm" "$dir/cli-off.pfm" || { ok=0; why="--guiding off does not override the file's 'guiding on'"; }
        ! cmp -s "$dir/file-on.pfm" "$dir/cli-off.pfm" || { ok=0; why="guiding on gave the unguided image"; }
        cmp -s "$dir/file-params.pfm" "$dir/cli-params.pfm" || { ok=0; why="the file's guiding_budget/alpha/memory != the options"; }
        ! cmp -s "$dir/file-params.pfm" "$dir/file-on.pfm" || { ok=0; why="guiding_budget 0.5, alpha 0.3 had no effect"; }
        [ -s "$dir/cli-auto.pfm" ] || { ok=0; why="--guiding auto wrote nothing"; }
    fi
    # the statistics say what guiding did
    "$P" "$dir/on.scene" --size 24x24 --spp 16 -o "$dir/s.pfm" >"$W/out.txt" 2>/dev/null
    grep -q '^guiding    guided: [0-9]* training iterations.*; training .* s, .* samples; guide .* KiB' "$W/out.txt" ||
        { ok=0; why="$why; no 'guiding' line in the statistics: $(grep guiding "$W/out.txt")"; }
    if [ $ok = 1 ]; then pass guiding "file statements = options (same bytes), overridden by them, change the image; statistics"
    else fail guiding "$why"; fi
    # --guide-at alone: only its picture, PFM 512 x 256, guiding turned on (the scene file says off)
    ok=1 why=""
    rm -rf "$dir/at" && mkdir -p "$dir/at"
    (cd "$dir/at" && "$P" "$dir/off.scene" --size 24x24 --spp 16 --guiding-memory 4 --guide-at 278 1 278 g.pfm) \
        >"$W/out.txt" 2>"$W/err.txt" || { ok=0; why="failed: $(head -n 1 "$W/err.txt")"; }
    # (the box's glass ball: the caustic photons' guide beside it)
    [ "$(ls "$dir/at" | tr '\n' ' ')" = "g-caustic.pfm g.pfm " ] ||
        { ok=0; why="$why; wrote '$(ls "$dir/at" | tr '\n' ' ')' (want g.pfm and g-caustic.pfm only)"; }
    for f in g.pfm g-caustic.pfm; do
        [ "$(head -c 14 "$dir/at/$f" 2>/dev/null | tr '\n' ' ')" = "PF 512 256 -1." ] || { ok=0; why="$why; $f header"; }
        [ "$(wc -c <"$dir/at/$f" 2>/dev/null)" = $((16 + 512 * 256 * 12)) ] || { ok=0; why="$why; $f size"; }
    done
    grep -q '^wrote      g-caustic.pfm$' "$W/out.txt" || { ok=0; why="$why; no 'wrote g-caustic.pfm'"; }
    grep -q 'guiding    guided: .*(turned on for --guide-at)' "$W/out.txt" || { ok=0; why="$why; no '(turned on for --guide-at)'"; }
    ! grep -q '^pdftrace: ' "$W/err.txt" || { ok=0; why="$why; stderr: $(grep '^pdftrace: ' "$W/err.txt")"; }
    # with -o as well, an 8-bit picture; too few samples to train: a warning, still written
    if [ $have_png = 1 ]; then f=g.png; else f=g.ppm; fi
    "$P" "$dir/on.scene" -q --size 8x8 --spp 2 -o "$dir/at/img.ppm" --guide-at=0 0 0 "$dir/at/$f" 2>"$W/err.txt"
    status=$?
    [ $status = 0 ] && [ -s "$dir/at/img.ppm" ] && [ -s "$dir/at/$f" ] || { ok=0; why="$why; with -o: status $status"; }
    grep -q "^pdftrace: warning: --guide-at: the guide learned nothing (not guided: too few samples" "$W/err.txt" ||
        { ok=0; why="$why; untrained guide: '$(head -n 1 "$W/err.txt")'"; }
    if [ $f = g.png ]; then
        [ "$(hexbytes "$dir/at/g.png" 12 16)" = 49484452000002000000010008020000 ] || { ok=0; why="$why; g.png IHDR"; }
    else
        [ "$(head -c 15 "$dir/at/g.ppm" | tr '\n' ' ')" = "P6 512 256 255 " ] || { ok=0; why="$why; g.ppm header"; }
    fi
    if [ $ok = 1 ]; then pass guide_at "alone: only 512x256 PFMs (the guide's, the caustic photons'), guiding turned on; $f with -o; an untrained guide warns"
    else fail guide_at "$why"; fi
    # the exports are the same with and without the guiding statements
    ok=1
    for f in plain with; do
        (cd "$dir/$f" && "$P" c.scene -q --export-pov c.pov --export-mitsuba c.xml) 2>"$W/err.txt" ||
            { ok=0; why="$f: $(head -n 1 "$W/err.txt")"; }
    done
    if [ $ok = 1 ] && cmp -s "$dir/plain/c.pov" "$dir/with/c.pov" && cmp -s "$dir/plain/c.xml" "$dir/with/c.xml"; then
        pass guiding_export "POV-Ray and Mitsuba exports ignore the guiding statements"
    else
        fail guiding_export "${why:-the exports differ with the guiding statements}"
    fi
    # a bad statement: status 2, file:line
    { cat "$S/mirror.scene"; printf 'guiding sometimes\n'; } >"$dir/bad.scene"
    f=$(($(wc -l <"$S/mirror.scene") + 1))
    if bad_case "guiding sometimes (scene file)" "$dir/bad.scene" -o "$W/bad/x.ppm" &&
        grep -q "bad.scene:$f: guiding: expected off, on or auto, got 'sometimes'" "$W/err.txt"; then
        pass guiding_statement "guiding sometimes: status 2, bad.scene:$f"
    else
        fail guiding_statement "'$(cat "$W/err.txt")'"
    fi
}

# ---- the environment statement: a map renders and exports to Mitsuba (the .xml and its
# resampled .env.pfm), the POV-Ray export refuses it; a missing file, a file that is not PFM,
# a transform that is not a rotation, a bad scale, a second map, a map outside the directory
# (unless --allow-path) and an .exr without OpenEXR each give status 2 and file:line; with
# OpenEXR, an .exr map (written by pdftrace itself) renders
t_environment() {
    local d=$W/env ok=1 head='camera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\nsphere 0 0 0 1 m\n'
    local status
    mkdir -p "$d/scene" "$d/shared" "$d/out"
    cp "$S/sky.pfm" "$d/scene/sky.pfm"
    cp "$S/sky.pfm" "$d/shared/sky.pfm"
    printf "${head}rotate 0 1 0 30\nenvironment sky.pfm 0.5\n" >"$d/scene/good.scene"
    "$P" "$d/scene/good.scene" -q --spp 2 --size 16x8 -o "$d/out/g.pfm" 2>"$W/err.txt" ||
        { fail environment "good.scene: $(head -n 1 "$W/err.txt")"; ok=0; }
    if ! (cd "$d/out" && "$P" "$d/scene/good.scene" -q --size 16x8 --export-mitsuba m.xml) 2>"$W/err.txt" ||
        [ "$(ls "$d/out" | tr '\n' ' ')" != "g.pfm m.env.pfm m.xml " ] ||
        ! grep -q '<emitter type="envmap"><string name="filename" value="m.env.pfm"/><float name="scale" value="0.5"/>' "$d/out/m.xml" ||
        [ "$(head -c 11 "$d/out/m.env.pfm")" != "$(printf 'PF\n256 257')" ]; then
        fail environment "Mitsuba export: '$(head -n 1 "$W/err.txt")', wrote $(ls "$d/out" | tr '\n' ' ')"
        ok=0
    fi
    bad_case "environment: POV-Ray export" "$d/scene/good.scene" --export-pov x.pov || ok=0
    grep -q "good.scene:5: POV-Ray export: an environment map has no POV-Ray equivalent" "$W/err.txt" ||
        { fail environment "POV-Ray export: '$(cat "$W/err.txt")'"; ok=0; }
    printf 'not a map\n' >"$d/scene/text.pfm"
    local cases=("environment missing.pfm|3: environment: no file 'missing.pfm' inside the scene's directory"
                 "environment text.pfm|3: environment: $d/scene/text.pfm: not a PFM file"
                 "scale 1 2 1\nenvironment sky.pfm|4: environment: the scene's current transform is not a rotation"
                 "environment sky.pfm 0|3: environment scale: must be > 0, got '0'"
                 "environment sky.pfm -2|3: environment scale: must be > 0, got '-2'"
                 "environment sky.pfm\nenvironment sky.pfm|4: environment: a second map (the first is at line 3"
                 "environment ../shared/sky.pfm|3: environment: no file '../shared/sky.pfm' inside the scene's directory")
    local c stmt want
    for c in "${cases[@]}"; do
        stmt=${c%%|*} want=${c#*|}
        printf "camera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n${stmt}\nidentity\nsphere 0 0 0 1 m\n" >"$d/scene/bad.scene"
        bad_case "$stmt" "$d/scene/bad.scene" -o x.ppm || { ok=0; continue; }
        grep -qF "bad.scene:$want" "$W/err.txt" || { fail environment "$stmt: '$(cat "$W/err.txt")', want 'bad.scene:$want'"; ok=0; }
    done
    printf "${head}environment ../shared/sky.pfm\n" >"$d/scene/allowed.scene"
    "$P" "$d/scene/allowed.scene" -q --spp 1 --size 8x8 --allow-path "$d/shared" -o "$d/out/a.pfm" 2>"$W/err.txt" ||
        { fail environment "--allow-path: $(cat "$W/err.txt")"; ok=0; }
    printf "${head}environment map.exr\n" >"$d/scene/exr.scene"
    if [ $have_exr = 1 ]; then # an .exr map: pdftrace's own 8 x 4 EXR image of the mirror scene
        "$P" "$S/mirror.scene" -q --spp 1 --size 8x4 -o "$d/scene/map.exr" &&
            "$P" "$d/scene/exr.scene" -q --spp 1 --size 8x8 -o "$d/out/e.pfm" 2>"$W/err.txt" ||
            { fail environment "an .exr map: $(cat "$W/err.txt")"; ok=0; }
    else
        bad_case "environment map.exr (no OpenEXR)" "$d/scene/exr.scene" -o x.ppm || ok=0
        grep -q "exr.scene:4: environment: 'map.exr': this program was built without OpenEXR" "$W/err.txt" ||
            { fail environment "an .exr without OpenEXR: '$(cat "$W/err.txt")'"; ok=0; }
    fi
    [ $ok = 1 ] && pass environment "renders; Mitsuba export with its map; POV-Ray refused; 7 bad statements with file:line; --allow-path; .exr $([ $have_exr = 1 ] && echo read || echo refused)"
}

# ---- --integrator: batched writes the scalar image byte for byte; the statistics say which ran
# (the default below AVX2: scalar), and the option overrides the scene file's statement
t_integrator() {
    local dir=$W/integrator ok=1 why=""
    mkdir -p "$dir"
    { cat "$S/glass.scene"; printf 'integrator batched\n'; } >"$dir/batched.scene"
    PDFTRACE_SIMD=sse2 "$P" "$S/glass.scene" --spp 2 --size 24x16 -o "$dir/s.pfm" >"$dir/s.txt" &&
        "$P" "$S/glass.scene" --spp 2 --size 24x16 --integrator batched -o "$dir/b.pfm" >"$dir/b.txt" &&
        "$P" "$dir/batched.scene" --spp 2 --size 24x16 -o "$dir/f.pfm" >"$dir/f.txt" &&
        "$P" "$dir/batched.scene" --spp 2 --size 24x16 --integrator scalar -o "$dir/o.pfm" >"$dir/o.txt" ||
        { ok=0; why="a render failed"; }
    if [ $ok = 1 ]; then
        cmp -s "$dir/s.pfm" "$dir/b.pfm" || { ok=0; why="--integrator batched changed the image"; }
        cmp -s "$dir/s.pfm" "$dir/f.pfm" || { ok=0; why="the scene's 'integrator batched' changed the image"; }
        grep -q '^integrator scalar$' "$dir/s.txt" || { ok=0; why="the default run below AVX2 does not say 'integrator scalar'"; }
        grep -q '^integrator batched$' "$dir/b.txt" || { ok=0; why="--integrator batched does not say so"; }
        grep -q '^integrator batched$' "$dir/f.txt" || { ok=0; why="the scene's statement was not applied"; }
        grep -q '^integrator scalar$' "$dir/o.txt" || { ok=0; why="--integrator scalar did not override the scene"; }
    fi
    if [ $ok = 1 ]; then pass integrator "batched = scalar byte for byte; stats line; scene statement and override"
    else fail integrator "$why"; fi
}

t_help
t_png_exr
t_precision_warning
t_bad_input
t_export_pov
t_export_mitsuba
t_default_output
t_preview
t_overrides
t_adaptive_mode
t_integrator
t_guiding
t_display
t_scene_limits
t_environment
t_signal
t_output_is_input
t_disk_full
echo "$passed passed, $failed failed, $skipped skipped"
[ $failed = 0 ]
