#!/usr/bin/env bash
# Checksums of every output the tool writes, for byte-identity checks across refactors:
#   scripts/checksums.sh BINARY OUT_DIR [MESH_DIR]
# writes OUT_DIR/sums.txt (sha256 per output) and OUT_DIR/log.txt. Compare two runs with `diff`.
# Covers every strategy but kmedoids-paper (its time budget makes the output depend on the machine),
# +refine-fast, +refine and +partition on every mesh, +refine-max on the meshes under 50k triangles,
# kmedoids-parallel at its default region size and at 1024, the GPU builds (`--device gpu`) of
# every strategy with a GPU path, the ordering passes, the glTF export, LOD files (meshopt and
# kmedoids on every mesh) and every compressed format.
set -euo pipefail
bin=$(realpath "$1"); out=$2; meshes=${3:-../shared/meshes}
mkdir -p "$out/files"; out=$(realpath "$out"); : > "$out/log.txt"
strategies="nvidia nvidia+tipsify greedy greedy-paper bsphere bsphere-paper bsphere-coherent bsphere-parallel
  kmedoids kmedoids-parallel kmedoids-flat compact meshopt meshopt-scan meshopt-spatial qem partition greedy+partition
  meshopt+refine meshopt+refine-fast greedy+refine-fast"
gpu_strategies="bsphere-parallel kmedoids-flat kmedoids-parallel"
formats="meshopt ts ts-compact ix ix-compact sc sc-compact gi gi-compact"
run() { echo "+ $*" >> "$out/log.txt"; "$bin" -q "$@" >> "$out/log.txt" 2>&1; }
for m in "$meshes"/*.ply.zst; do
  n=$(basename "$m" .ply.zst); f=$out/files/$n
  small=$( (zstdcat "$m" 2>/dev/null || true) | head -c 4096 | grep -a -m1 'element face' | awk '{print ($3 < 50000)}')
  for s in $strategies; do run build -s "$s" -o "$f.build.$s.mlt" "$m"; done
  run build -s kmedoids-parallel --kmedoids-regions 1024 -o "$f.build.kmedoids-parallel-1024.mlt" "$m"
  for s in $gpu_strategies; do run build --device gpu -s "$s" -o "$f.build-gpu.$s.mlt" "$m"; done
  if [ "$small" = 1 ]; then run build -s meshopt+refine-max -o "$f.build.meshopt+refine-max.mlt" "$m"; fi
  run build -s meshopt --local-order --meshlet-order triangles -o "$f.build.meshopt-ordered.mlt" "$m"
  run export -s kmedoids -o "$f.export.kmedoids.glb" "$m"
  run lod -o "$f.lod.meshopt.lod" "$m"
  run lod -s kmedoids -o "$f.lod.kmedoids.lod" "$m"
  for c in $formats; do run compress -f "$c" -o "$f.compress.$c.bin" "$m"; done
  run compress -f laced-wires -s qem -l 64/84 -o "$f.compress.laced-wires.bin" "$m"
done
(cd "$out/files" && sha256sum -- * > "$out/sums.txt")
rm -r "$out/files"
echo "$(wc -l < "$out/sums.txt") outputs in $out/sums.txt"
