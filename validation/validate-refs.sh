#!/usr/bin/env bash
# validate-refs.sh - `make validate-refs`: re-renders the POV-Ray references that are too slow
# for a routine `make validate` (the recipe's "high" radiosity) into scenes/ref/. The exact
# commands (also in scenes/ref/README.md), for cornell-diffuse at 128 x 128 (~12 min, 2 cores):
#   build/ptv pov scenes/cornell-diffuse.scene build/ref/cornell-diffuse-high.pov high 128 128
#   povray +Ibuild/ref/cornell-diffuse-high.pov +Obuild/ref/cornell-diffuse.exr +FE +W128 +H128 +A0.0 +AM2 +R4 -D -V -GA
#   cp build/ref/cornell-diffuse.exr scenes/ref/cornell-diffuse.exr
set -euo pipefail
ptv=$1
command -v povray >/dev/null || { echo "validate-refs: povray is not installed" >&2; exit 1; }
mkdir -p build/ref
for name in cornell-diffuse; do
    "$ptv" pov "scenes/$name.scene" "build/ref/$name-high.pov" high 128 128
    rm -f "build/ref/$name.exr"
    echo "rendering build/ref/$name.exr with POV-Ray (high radiosity; about 12 minutes on 2 cores)"
    povray +I"build/ref/$name-high.pov" +O"build/ref/$name.exr" +FE +W128 +H128 +A0.0 +AM2 +R4 -D -V -GA \
        >"build/ref/$name.log" 2>&1 || { echo "validate-refs: povray failed, see build/ref/$name.log" >&2; exit 1; }
    cp "build/ref/$name.exr" "scenes/ref/$name.exr"
    echo "wrote scenes/ref/$name.exr"
done
