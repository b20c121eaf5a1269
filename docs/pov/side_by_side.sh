#!/bin/sh
# Side-by-side renders of POV-Ray example scenes: POV-Ray 3.7 (Debian's `povray`) on the left,
# Photonix on the right, 160x120 each, written to docs/images/pov-side/<scene>.jpg. Photonix's
# side is denoised (Open Image Denoise, which ci/setup installs; DENOISE=0 for the raw render).
# Needs: apt-get install povray povray-examples povray-includes; python3 with PIL.
#   docs/pov/side_by_side.sh [PHOTONIX_BINARY]
set -u
BIN=${1:-target/release/photonix}
DENOISE_FLAG=--denoise
[ "${DENOISE:-1}" = 0 ] && DENOISE_FLAG=
EX=/usr/share/doc/povray/examples
OUT=docs/images/pov-side
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
# SCENES="a/b c/d" renders only those.
for s in ${SCENES:-interior/caustic2 radiosity/radiosity2 camera/focalblur lights/arealit1 interior/media/media1 \
         interior/fog_std lights/glassthing advanced/woodbox textures/patterns/crackle1 objects/lathe1a \
         objects/quartic/torus objects/blob incdemo/circletext advanced/sunsethf interior/skysph1 \
         textures/pigments/txtrmap textures/patterns/radial textures/pigments/pigmap lights/shadows}; do
    n=$(basename "$s")
    # POV-Ray: its own defaults at this size, antialiasing off, no display.
    (cd "$(dirname "$EX/$s.pov")" && timeout 120 povray +I"$n.pov" +O"$TMP/$n-pov.png" +W160 +H120 -D -GA +FN \
        +L/usr/share/povray-3.7/include >/dev/null 2>&1) || echo "$s: povray failed"
    timeout 300 "$BIN" render "$EX/$s.pov" --backend cpu --resolution 160x120 --spp 16 --passes 4 $DENOISE_FLAG \
        -o "$TMP/$n-px.png" >/dev/null 2>&1 || echo "$s: photonix failed"
    python3 - "$TMP/$n-pov.png" "$TMP/$n-px.png" "$OUT/$n.jpg" <<'PY'
import sys
from PIL import Image
a, b, out = sys.argv[1:4]
imgs = []
for p in (a, b):
    try:
        imgs.append(Image.open(p).convert("RGB").resize((160, 120)))
    except Exception:
        imgs.append(Image.new("RGB", (160, 120), (128, 0, 128)))
pair = Image.new("RGB", (324, 120), (255, 255, 255))
pair.paste(imgs[0], (0, 0))
pair.paste(imgs[1], (164, 0))
pair.save(out, quality=85)
PY
done
