#!/usr/bin/env bash
# Installs femreg into a temporary prefix, builds examples/track_sequence against it with
# find_package(femreg), and runs it on two frames of the demo.
set -euo pipefail
build_dir=$1
source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir/examples/track_sequence" -B "$work/example" \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/example" >/dev/null
LD_LIBRARY_PATH="$work/prefix/lib:${LD_LIBRARY_PATH:-}" "$work/example/track_sequence" \
  "$source_dir/datasets/demo/scene.yaml" \
  "$source_dir/datasets/demo/clouds/frame_0000.pcd" "$source_dir/datasets/demo/clouds/frame_0001.pcd" \
  | tee "$work/out.txt"
grep -q "frame 1:" "$work/out.txt"
