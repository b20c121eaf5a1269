#!/bin/sh
# Cost per camera sample by material kind: the Cornell box with its white surfaces (floor,
# ceiling, back wall, both blocks) made of one kind at a time, rendered for one pass with the
# scene's photon settings; prints the camera kernel's seconds per sample (render time / pixels /
# spp; photons apart) and rays per sample. Textured kinds use the same reflectance through a
# pattern or an image texture (the kernels' textured variant on the GPU).
# Usage: benches/material_kinds.sh [photonix binary]; BACKENDS="cpu gpu" RES=128x128 SPP=4.
set -eu
bin=${1:-target/release/photonix}
backends=${BACKENDS:-"cpu gpu"}
res=${RES:-128x128}
spp=${SPP:-4}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir -p "$dir/textures"
cp scenes/textures/cornell-back-wall.png "$dir/textures/"
pixels=$(echo "$res" | awk -Fx '{ print $1 * $2 }')

kind() {
    name=$1
    shift
    # The box with [materials.white] (its 4 lines) replaced.
    awk 'BEGIN { skip = 0 } /^\[materials\.white\]/ { skip = 3; next } skip > 0 { skip--; next } { print }' \
        scenes/cornell-box.toml > "$dir/$name.toml"
    printf '%s\n' "$@" >> "$dir/$name.toml"
}
kind diffuse '[materials.white]' 'type = "diffuse"' 'reflectance = [0.725, 0.71, 0.68]'
kind mirror '[materials.white]' 'type = "mirror"' 'tint = [0.725, 0.71, 0.68]'
kind conductor-smooth '[materials.white]' 'type = "conductor"' 'preset = "silver"'
kind conductor-rough '[materials.white]' 'type = "conductor"' 'preset = "silver"' 'roughness = 0.3'
kind dielectric '[materials.white]' 'type = "dielectric"' 'ior = 1.5'
kind dielectric-rough '[materials.white]' 'type = "dielectric"' 'ior = 1.5' 'roughness = 0.3'
kind plastic '[materials.white]' 'type = "plastic"' 'reflectance = [0.725, 0.71, 0.68]' 'roughness = 0.2'
kind mix '[materials.matte]' 'type = "diffuse"' 'reflectance = [0.725, 0.71, 0.68]' \
    '[materials.shiny]' 'type = "plastic"' 'reflectance = [0.725, 0.71, 0.68]' 'roughness = 0.2' \
    '[materials.white]' 'type = "mix"' 'materials = ["matte", "shiny"]' 'weight = 0.5'
kind diffuse-pattern '[textures.marble]' 'type = "pattern"' 'pattern = "marble"' 'turbulence = 0.8' \
    'color_map = [[0.0, [0.725, 0.71, 0.68]], [1.0, [0.5, 0.5, 0.5]]]' 'transform = { scale = 100 }' \
    '[materials.white]' 'type = "diffuse"' 'reflectance = { texture = "marble" }'
kind diffuse-image '[textures.wall]' 'type = "image"' 'file = "textures/cornell-back-wall.png"' \
    '[materials.white]' 'type = "diffuse"' 'reflectance = { texture = "wall" }'

printf '%-8s %-18s %9s %9s %12s %10s\n' backend kind photons_s render_s us/sample rays/sample
for backend in $backends; do
    for scene in diffuse mirror conductor-smooth conductor-rough dielectric dielectric-rough plastic mix diffuse-pattern diffuse-image; do
        log=$("$bin" render "$dir/$scene.toml" --backend "$backend" --passes 1 --spp "$spp" --resolution "$res" -o "$dir/$scene.exr" 2>&1) ||
            { echo "$scene: $log" >&2; exit 1; }
        photons=$(echo "$log" | sed -n 's/.*, photons \([0-9.]*\) s.*/\1/p' | head -1)
        seconds=$(echo "$log" | sed -n 's/.*render \([0-9.]*\) s.*/\1/p')
        rays=$(echo "$log" | sed -n 's/.*(\([0-9]*\) rays).*/\1/p')
        awk -v b="$backend" -v k="$scene" -v p="${photons:--}" -v s="$seconds" -v r="$rays" -v n="$((pixels * spp))" \
            'BEGIN { printf "%-8s %-18s %9s %9.3f %12.2f %10.2f\n", b, k, p, s, s * 1e6 / n, r / n }'
    done
done
