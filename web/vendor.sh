#!/usr/bin/env bash
# Refreshes web/vendor/ from npm: three.js (its core and the OrbitControls and TransformControls
# addons), minified into ES modules. The page loads them through an import map; the binary embeds
# them (src/editor/assets.rs), so neither the build nor `photonix serve` needs npm. To update,
# change the versions in package.json, run this script and commit web/vendor/.
set -euo pipefail
cd "$(dirname "$0")"
npm install --no-audit --no-fund --silent
esbuild=node_modules/.bin/esbuild
three=node_modules/three
"$esbuild" "$three/build/three.module.js" --bundle --format=esm --minify --legal-comments=inline \
    --outfile=vendor/three.module.min.js --log-level=warning
for addon in OrbitControls TransformControls; do  # imports of "three" point at the vendored file
    "$esbuild" "$three/examples/jsm/controls/$addon.js" --bundle --format=esm --minify --external:three \
        --legal-comments=inline --outfile="vendor/$addon.min.js" --log-level=warning
    # No import map needed (the page's Content-Security-Policy allows no inline script).
    sed -i 's|from"three"|from"./three.module.min.js"|g' "vendor/$addon.min.js"
done
cp "$three/LICENSE" vendor/three.LICENSE
echo "three $(node -p "require('./$three/package.json').version") vendored into web/vendor/"
