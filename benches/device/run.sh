#!/usr/bin/env bash
# On a lent GPU machine, from the repository root, with .device/ carried (benches/device/pack.sh):
# the Vulkan loader, every packed binary, then
#   1. benches/gpu_check.sh with the newest binary (its default target, relMSE 0.001; cap 30 s);
#   2. cornell-glossy and cornell-box at 256 passes with each binary (stage times, GPU time);
#   3. benches/time_to_quality.py with every binary against Mitsuba's cuda_ad_rgb (2 s and 10 s
#      budgets, the four shared scenes);
#   4. when packed, the bidirectional twins' tests (tests/integrators.rs) on the device's GPU.
# About 4 minutes for two binaries on an H200; outputs under $OUT (logs, ttq.json, table.md).
set -u
export PYTHONUNBUFFERED=1 TIMEFORMAT='wall %R s, cpu %U+%S s'
out=${OUT:-/tmp/device-out}
mkdir -p "$out"
for f in .device/gl/*.deb; do dpkg -x "$f" /; done; ldconfig
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $icd ] && export VK_DRIVER_FILES=$icd
mkdir -p /tmp/photonix-bin /tmp/photonix-py
bins=()
for x in .device/bin/*.xz; do
    b=/tmp/photonix-bin/$(basename "$x" .xz)
    xz -d -c "$x" > "$b" && chmod +x "$b" && bins+=("$b")
done
newest=${bins[${#bins[@]}-1]}
"$newest" devices | tee "$out/devices.txt"
xz -d -c .device/mitsuba.tar.xz | tar xf - -C /tmp/photonix-py
export PYTHONPATH=/tmp/photonix-py
py=/opt/torch/.venv/bin/python3; [ -x $py ] || py=python3
mkdir -p ../shared && cp -r .device/reference ../shared/
# The driver compiles each binary's pipelines on its first render and caches them on disk:
# warm the cache so the timed runs see what a user's second render sees.
for b in "${bins[@]}"; do
    for s in box caustics fog glossy; do "$b" render scenes/cornell-$s.toml --backend gpu --passes 1 -o /tmp/w.exr 2>/dev/null; done
done
timeout 120 bash benches/gpu_check.sh --photonix "$newest" --references .device/reference --cap 30 \
    --out /tmp/gpu-check 2>&1 | tee "$out/gpu_check.log"
cp /tmp/gpu-check/table.md "$out/" 2>/dev/null
{ for s in glossy box; do for b in "${bins[@]}"; do
    echo "== cornell-$s $(basename "$b")"
    { time "$b" render scenes/cornell-$s.toml --backend gpu --passes 256 -o /tmp/p.exr 2>&1 | grep -E 'pass|prepare|gpu time'; } 2>&1
    "$b" diff /tmp/p.exr .device/reference/cornell-$s/reference.exr | head -3
done; done; } 2>&1 | tee "$out/passes256.log"
args=()
for b in "${bins[@]}"; do args+=(--photonix "$b"); done
variant=cuda_ad_rgb
$py -c "import mitsuba as mi; mi.set_variant('cuda_ad_rgb')" 2>/dev/null || variant=scalar_rgb
timeout 300 $py benches/time_to_quality.py "${args[@]}" --backends gpu --budgets 2,10 \
    --scenes cornell-box,cornell-caustics,cornell-glossy,cornell-fog --variant $variant \
    --spp 64,256,1024,4096 --floor-spp 2048 --json "$out/ttq.json" 2>&1 | tee "$out/ttq.log"
if [ -f .device/integrators.xz ]; then
    xz -d -c .device/integrators.xz > /tmp/photonix-bin/integrators && chmod +x /tmp/photonix-bin/integrators
    timeout 240 /tmp/photonix-bin/integrators --test-threads 4 bpt_and_vcm_gpu_match_cpu paths_per_invocation \
        loop_limit 2>&1 | tail -15 | tee "$out/tests.log"
fi
