#!/bin/sh
# Adaptive area lights against the plain grid at equal time. A disc lamp beside a ball over a
# plane (tests/lights.rs's penumbra scene at 128x128), direct light only, so the shadow rays are
# the whole noise. Renders a long plain reference on the CPU, then the 3 x 3 grid with and
# without `adaptive = 1` on each backend at the same passes, and prints each one's render time,
# rays, relMSE against the reference and relMSE x time (lower is better: relMSE falls as 1/time,
# so this is the error at equal time up to a constant).
# Usage: benches/adaptive.sh [photonix binary]; BACKENDS="cpu gpu" PASSES=4 SPP=36 (per pass).
set -eu
bin=${1:-target/release/photonix}
backends=${BACKENDS:-"cpu gpu"}
passes=${PASSES:-4}
spp=${SPP:-36}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

scene() {
    cat > "$dir/$1.toml" <<SCENE
[camera]
position = [0, 6, 0]
look_at = [0, 0, 0]
up = [0, 0, 1]
fov = 60
resolution = [128, 128]

[render]
max_depth = 4
seed = 5
spp = $spp

[photons]
enabled = false

[materials.plane]
type = "diffuse"
reflectance = 0.5

[materials.ball]
type = "diffuse"
reflectance = 0.5

[[shapes]]
type = "quad"
material = "plane"
vertices = [[-50, 0, -50], [-50, 0, 50], [50, 0, 50], [50, 0, -50]]

[[shapes]]
type = "sphere"
material = "ball"
center = [0, 0.5, 0]
radius = 0.5

[[lights]]
type = "area"
shape = "disc"
center = [-2, 2, 0]
normal = [0, -1, 0]
radius = 0.75
radiance = 20
$2
SCENE
}
scene plain ""
scene grid 'samples = [3, 3]'
scene adaptive 'samples = [3, 3]
adaptive = 1'

echo "reference: plain sampling, 64 passes x $spp spp on the CPU backend"
"$bin" render "$dir/plain.toml" --backend cpu --passes 64 -o "$dir/reference.exr" > /dev/null 2>&1
printf '%-8s %-9s %6s %9s %10s %10s %12s\n' backend light spp render_s rays relMSE relMSE_x_s
for backend in $backends; do
    for light in grid adaptive; do
        log=$("$bin" render "$dir/$light.toml" --backend "$backend" --passes "$passes" -o "$dir/$light-$backend.exr" 2>&1)
        seconds=$(echo "$log" | sed -n 's/.*render \([0-9.]*\) s.*/\1/p')
        rays=$(echo "$log" | sed -n 's/.*(\([0-9]*\) rays).*/\1/p')
        error=$("$bin" diff "$dir/$light-$backend.exr" "$dir/reference.exr" | sed -n 's/^relMSE[^0-9]*\([0-9.eE+-]*\).*/\1/p')
        product=$(awk "BEGIN { printf \"%.3e\", $error * $seconds }")
        printf '%-8s %-9s %6s %9s %10s %10s %12s\n' "$backend" "$light" $((passes * spp)) "$seconds" "$rays" "$error" "$product"
    done
done
