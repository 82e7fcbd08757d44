# Sourced by the texel benchmarks (texels.sh, stages.sh, texels_process.sh), from the
# repository's root with $texels set: NEW is this tree's release binary unless given,
# and $data the texel batch of benches/texels.py with $texels scans, generated once into
# $TEXELS_DIR (default /tmp/goniofit-texels), never into the repository.
if [ -z "${NEW:-}" ]; then
  cargo build --release --quiet
  NEW=${CARGO_TARGET_DIR:-$PWD/target}/release/goniofit
fi
dir=${TEXELS_DIR:-/tmp/goniofit-texels}
mkdir -p "$dir"
data=$dir/texels-$texels.csv
if [ ! -s "$data" ]; then
  python3 benches/texels.py gen --goniofit "$NEW" --texels "$texels" --out "$data"
fi
