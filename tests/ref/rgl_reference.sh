#!/bin/sh
# Regenerate tests/ref/rgl_reference.csv with RGL's own loader (see rgl_reference.cpp).
# Usage: tests/ref/rgl_reference.sh BRDF_LOADER_DIR
#   BRDF_LOADER_DIR: a checkout of github.com/rgl-epfl/brdf-loader (commit c9ea6f9f),
#   holding powitacq_rgb.h and powitacq_rgb.inl.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
loader=${1:?usage: $0 BRDF_LOADER_DIR}
bin=$(mktemp -d)/rgl_reference
g++ -O2 -std=c++17 -I"$loader" "$here/rgl_reference.cpp" -o "$bin"
"$bin" "$here"/../../data/rgl-epfl/*.bsdf > "$here/rgl_reference.csv"
echo "wrote $here/rgl_reference.csv ($(wc -l < "$here/rgl_reference.csv") lines)"
