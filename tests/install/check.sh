#!/usr/bin/env bash
# check.sh - `make install-check`: installs pdftrace into a temporary prefix and builds a program
# against the installed copy the way a user would, with nothing from the source tree:
#   cc $(pkg-config --cflags pdftrace) hello.c $(pkg-config --libs pdftrace)
# Then: the installed scene and EXR headers compile on their own (when installed; the EXR one
# only where OpenEXR's headers are found), DESTDIR staging keeps the prefix out of the .pc file,
# and `make uninstall` removes every file that `make install` wrote.
# Environment (the Makefile passes them): MAKE, CC, BUILD.
set -euo pipefail
cd "$(dirname "$0")/../.."
make=${MAKE:-make}
cc=${CC:-cc}
build=${BUILD:-build}
fail() { printf 'install-check: FAILED: %s\n' "$*" >&2; exit 1; }
command -v pkg-config >/dev/null || fail "pkg-config is not installed (apt-get install pkg-config)"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
mkdir -p "$tmp/work"
cp tests/install/hello.c "$tmp/work/"

"$make" --no-print-directory install PREFIX="$prefix" BUILD="$build" >"$tmp/install.log" ||
    { cat "$tmp/install.log"; fail "make install PREFIX=$prefix"; }
headers=$(cd "$prefix/include" && ls pdftrace*.h)
echo "installed into $prefix: include/{$(echo $headers | tr ' ' ',')}, lib/pkgconfig/pdftrace.pc$([ -e "$prefix/bin/pdftrace" ] && echo ', bin/pdftrace')"
for h in pdftrace*.h; do [ -f "$prefix/include/$h" ] || fail "include/$h was not installed"; done
[ -f "$prefix/lib/pkgconfig/pdftrace.pc" ] || fail "lib/pkgconfig/pdftrace.pc was not installed"
if [ -f tools/pdftrace.c ]; then
    [ -x "$prefix/bin/pdftrace" ] || fail "bin/pdftrace was not installed"
    "$prefix/bin/pdftrace" --version || fail "the installed bin/pdftrace --version"
fi

export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
cflags=$(pkg-config --cflags pdftrace)
libs=$(pkg-config --libs pdftrace)
version=$(pkg-config --modversion pdftrace)
want=$(awk '$1 == "#define" && $2 ~ /^PDFTRACE_VERSION_(MAJOR|MINOR|PATCH)$/ { v = v (v == "" ? "" : ".") $3 } END { print v }' pdftrace.h)
[ "$version" = "$want" ] || fail "pkg-config --modversion pdftrace is '$version', pdftrace.h says '$want'"
echo "pkg-config pdftrace $version: --cflags '$cflags' --libs '$libs'"

# shellcheck disable=SC2086
(cd "$tmp/work" && "$cc" $cflags hello.c -o hello $libs) || fail "$cc $cflags hello.c $libs"
"$tmp/work/hello" || fail "the program built against the installed header"

if [ -f "$prefix/include/pdftrace_scene.h" ]; then
    printf '#define PDFTRACE_IMPLEMENTATION\n#define PDFTRACE_SCENE_IMPLEMENTATION\n#include <pdftrace_scene.h>\nint main(void) { return 0; }\n' >"$tmp/work/scene.c"
    # shellcheck disable=SC2086
    (cd "$tmp/work" && "$cc" $cflags scene.c -o scene $libs && ./scene) || fail "a program including the installed pdftrace_scene.h"
    echo "pdftrace_scene.h: builds from the install alone"
fi
if [ -f "$prefix/include/pdftrace_exr.h" ]; then
    if pkg-config --exists OpenEXR; then
        exr=$(pkg-config --cflags-only-I OpenEXR)
        printf '#define PDFTRACE_IMPLEMENTATION\n#define PDFTRACE_EXR_IMPLEMENTATION\n#include <pdftrace_exr.h>\n' >"$tmp/work/exr.c"
        # shellcheck disable=SC2086
        (cd "$tmp/work" && "$cc" $cflags $exr -c exr.c -o exr.o) || fail "compiling the installed pdftrace_exr.h"
        echo "pdftrace_exr.h: compiles from the install alone"
    else
        echo "pdftrace_exr.h: not compiled (no OpenEXR headers found by pkg-config)"
    fi
fi

# DESTDIR: files under the staging directory, the .pc file naming the final prefix
stage=$tmp/stage
"$make" --no-print-directory install DESTDIR="$stage" PREFIX=/opt/pdftrace BUILD="$build" >"$tmp/install.log" ||
    { cat "$tmp/install.log"; fail "make install DESTDIR=$stage PREFIX=/opt/pdftrace"; }
[ -f "$stage/opt/pdftrace/include/pdftrace.h" ] || fail "DESTDIR: no $stage/opt/pdftrace/include/pdftrace.h"
grep -qx 'prefix=/opt/pdftrace' "$stage/opt/pdftrace/lib/pkgconfig/pdftrace.pc" ||
    fail "DESTDIR: the .pc file does not say prefix=/opt/pdftrace"
echo "DESTDIR=$stage PREFIX=/opt/pdftrace: staged, .pc says prefix=/opt/pdftrace"

# uninstall leaves nothing but empty directories
for args in "PREFIX=$prefix" "DESTDIR=$stage PREFIX=/opt/pdftrace"; do
    # shellcheck disable=SC2086
    "$make" --no-print-directory uninstall $args BUILD="$build" >"$tmp/uninstall.log" ||
        { cat "$tmp/uninstall.log"; fail "make uninstall $args"; }
done
left=$(find "$prefix" "$stage" -type f)
[ -z "$left" ] || fail "make uninstall left: $left"
echo "make uninstall: every installed file removed"
echo "install-check: ok"
