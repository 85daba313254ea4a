#!/usr/bin/env bash
# Builds the fuzz targets with clang's libFuzzer (+ ASan/UBSan) and runs each for SECONDS
# (default 60), starting from the seed corpus in tests/fuzz/corpus/<target>/. Findings are written
# to build-fuzz/findings/; a crash input becomes a regression test (tests/test_npy.cpp,
# tests/test_mesh_files.cpp).
# Usage: bash tests/fuzz/run.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-60}"
out=build-fuzz
mkdir -p "$out/findings"
flags=(-std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
       -Iinclude -I/usr/include/eigen3)
clang++ "${flags[@]}" -Isrc tests/fuzz/fuzz_npy.cpp src/io/npy.cpp src/input/samples.cpp src/io/atomic_file.cpp src/io/file_checks.cpp \
  -ltbb -o "$out/fuzz_npy"
clang++ "${flags[@]}" -Isrc tests/fuzz/fuzz_mesh_files.cpp src/io/mesh_files.cpp -o "$out/fuzz_mesh_files"
# The OpenVDB module is linked in (openvdb_loader.cpp then uses it instead of loading it).
vdb=(-DSDFCONTOUR_BUILD_MODULE_DIR='""' -DSDFCONTOUR_INSTALL_MODULE_DIR='""'
     -DSDFCONTOUR_INSTALL_MODULE_RELATIVE_DIR='""' src/io/vdb.cpp src/io/vdb_replies.cpp
     src/io/openvdb_loader.cpp src/io/openvdb_module.cpp src/io/isolated_call.cpp src/input/samples.cpp
     src/io/atomic_file.cpp src/io/file_checks.cpp -lopenvdb -lImath-3_1 -ltbb)
clang++ "${flags[@]}" -Isrc tests/fuzz/fuzz_vdb.cpp "${vdb[@]}" -o "$out/fuzz_vdb"
# The reading child's replies, parsed in-process (the child's own reads are fuzz_vdb's).
clang++ "${flags[@]}" -Isrc tests/fuzz/fuzz_vdb_replies.cpp "${vdb[@]}" -o "$out/fuzz_vdb_replies"
# Option values as text: the one number parser and every option's range.
clang++ "${flags[@]}" -Isrc tests/fuzz/fuzz_options.cpp src/pipeline/option_ranges.cpp -o "$out/fuzz_options"
# Meshes through sample's checks, union and signed distance (CGAL, TBB).
clang++ "${flags[@]}" -Isrc -DCGAL_DISABLE_ROUNDING_MATH_CHECK tests/fuzz/fuzz_mesh_sample.cpp \
  src/input/mesh_sdf.cpp src/input/mesh_union.cpp src/metrics/mesh_properties.cpp src/metrics/self_intersections.cpp src/metrics/triangle_pairs.cpp \
  src/reconstruction/carving_triangles.cpp src/reconstruction/triangle_cells.cpp src/input/parallel_select.cpp \
  src/reconstruction/nearest_triangles.cpp src/reconstruction/mesh_geometry.cpp \
  src/input/coordinates.cpp src/input/signed_distance.cpp src/input/samples.cpp src/input/mesh_transform.cpp \
  -ltbb -lgmp -lmpfr -o "$out/fuzz_mesh_sample"
# OpenVDB reads in a child process (src/io/isolated_call.h; its sanitizer reports on hostile files are
# printed but end only the child, which the parent reports as an error), which inherits libFuzzer's malloc limit:
# a huge allocation there is the child's failure, which the parent turns into an error, so only
# ASan's own size limit applies to it.
declare -A extra=([npy]="" [mesh_files]="" [vdb]="-malloc_limit_mb=1000000" [mesh_sample]=""
                  [options]="" [vdb_replies]="")
# Every target runs, even after one finds something; the script then fails naming them.
failed=()
for target in npy mesh_files vdb vdb_replies mesh_sample options; do
  corpus="$out/corpus_$target"
  mkdir -p "$corpus"
  cp tests/fuzz/corpus/$target/* "$corpus/"
  if ! "$out/fuzz_$target" "$corpus" -max_total_time="$seconds" -max_len=20000 -rss_limit_mb=2048 \
    -artifact_prefix="$out/findings/${target}_" ${extra[$target]} > "$out/$target.log" 2>&1; then
    failed+=("$target")
  fi
  echo "== $target"; tail -n 12 "$out/$target.log"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz findings in: ${failed[*]} (inputs in $out/findings/)" >&2
  exit 1
fi
