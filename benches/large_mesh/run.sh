#!/bin/bash
# A generated mesh of about 3.5 M triangles through lavapipe and the CPU backend: time, peak
# memory (maximum resident set) and GPU = CPU (BENCHMARKS.md, "Scene arrays in pages").
#   benches/large_mesh/run.sh [DIR] [INTEGRATOR...]
set -e
dir=${1:-/tmp/large-mesh}
shift || true
integrators=${*:-pt}
bin=${PHOTONIX:-target/release/photonix}
[ -f "$dir/scene.toml" ] || python3 "$(dirname "$0")/generate.py" "$dir"
for integrator in $integrators; do
  for backend in gpu cpu; do
    /usr/bin/time -f "$integrator $backend: wall %e s, cpu %U+%S s, max RSS %M KiB" \
      "$bin" render "$dir/scene.toml" --backend $backend --integrator "$integrator" \
      -o "$dir/$integrator-$backend.exr" 2>&1 | grep -v "^  gpu time"
  done
  "$bin" diff "$dir/$integrator-gpu.exr" "$dir/$integrator-cpu.exr" 2>&1 | tail -3 || true
done
