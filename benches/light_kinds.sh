#!/bin/sh
# Cost of each light kind per shadow ray: the Cornell box's geometry lit by one light of each
# kind in turn (the ceiling quad, a sphere lamp, a disc lamp, a point, a spot, a sharp and a soft
# distant light, a uniform environment and the physical sky without its sun), each timed by `photonix bench` (shadow rays are the extra time of a frame with one
# shadow ray per diffuse hit). Usage: benches/light_kinds.sh [photonix binary] [bench args...]
set -eu
bin=${1:-target/release/photonix}
[ $# -gt 0 ] && shift
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# The box without its light: everything before the [[lights]] table.
sed '/^\[\[lights\]\]/,$d' scenes/cornell-box.toml > "$dir/box.toml"
run() {
    name=$1
    shift
    { cat "$dir/box.toml"; printf '[[lights]]\n'; printf '%s\n' "$@"; } > "$dir/$name.toml"
    echo "== $name"
    "$bin" bench "$dir/$name.toml" $BENCH_ARGS
}
BENCH_ARGS="$*"
run area-quad 'type = "area"' 'shape = "quad"' 'vertices = [[343, 548.7, 227], [343, 548.7, 332], [213, 548.7, 332], [213, 548.7, 227]]' 'radiance = [17, 12, 4]'
run area-sphere 'type = "area"' 'shape = "sphere"' 'center = [278, 500, 279.5]' 'radius = 40' 'radiance = 10'
run area-disc 'type = "area"' 'shape = "disc"' 'center = [278, 548.7, 279.5]' 'normal = [0, -1, 0]' 'radius = 65' 'radiance = [17, 12, 4]'
run point 'type = "point"' 'position = [278, 540, 279.5]' 'intensity = 100000'
run spot 'type = "spot"' 'position = [278, 540, 279.5]' 'point_at = [278, 0, 279.5]' 'intensity = 100000' 'inner_angle = 30' 'outer_angle = 50'
run distant 'type = "distant"' 'direction = [0.2, -1, 0.3]' 'irradiance = 1'
run distant-soft 'type = "distant"' 'direction = [0.2, -1, 0.3]' 'irradiance = 1' 'angular_diameter = 10'
# An environment has no [[lights]] entry: a uniform sky instead of the light.
echo "== environment"
{ cat "$dir/box.toml"; printf '[environment]\ntype = "uniform"\nradiance = 1\n'; } > "$dir/environment.toml"
"$bin" bench "$dir/environment.toml" $BENCH_ARGS
echo "== sky"
{ cat "$dir/box.toml"; printf '[environment]\ntype = "sky"\nsun_elevation = 40\nsun_azimuth = 30\nsun = false\n'; } > "$dir/sky.toml"
"$bin" bench "$dir/sky.toml" $BENCH_ARGS
