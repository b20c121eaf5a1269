#!/usr/bin/env bash
# Packs what a lent GPU machine needs to measure Photonix against Mitsuba 3's CUDA path tracer
# into .device/ (ignored by git; the device tool carries it): stripped and xz-compressed release
# binaries, the shared references, a slimmed Mitsuba wheel (cuda_ad_rgb and scalar_rgb only: the
# whole wheel is 63 MB, over the 64 MiB a call carries with the tree), and the Vulkan loader's
# Debian packages. Run it here, then on the device (in one `run` call, carry [".device"]):
#
#   benches/device/pack.sh [BINARY ...]        # default: target/release/photonix
#   benches/device/run.sh                       # there: gpu_check, 256-pass stages, time to quality
#
# Each BINARY is packed under its own name plus the commit it was built from when it is
# target/release/photonix (photonix-<short hash>), so run.sh can compare builds in one run.
# Needs pip (to download the cp312 wheels the device's Python takes) and apt-get download.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=.device
mkdir -p "$out/bin"
grep -qx '/.device/' .git/info/exclude 2>/dev/null || echo '/.device/' >> .git/info/exclude
[ $# -gt 0 ] || set -- target/release/photonix
rm -f "$out"/bin/*.xz
for binary in "$@"; do
    [ -x "$binary" ] || { echo "pack: no binary at $binary" >&2; exit 1; }
    name=$(basename "$binary")
    [ "$binary" = target/release/photonix ] && name="photonix-$(git rev-parse --short HEAD)"
    tmp=$(mktemp)
    cp "$binary" "$tmp" && strip "$tmp"
    xz -T2 -6 -c "$tmp" > "$out/bin/$name.xz"
    rm -f "$tmp"
done
# The bidirectional twins' tests (GPU = CPU, runs of paths per invocation), when built
# (`cargo test --release --test integrators --no-run`): run.sh runs them on the device's GPU.
# They add about 8 MB: with them, pack one Photonix binary, or the call may pass its 64 MiB.
rm -f "$out/integrators.xz"
tests=$(ls -t target/release/deps/integrators-* 2>/dev/null | grep -v '\.d$' | head -1 || true)
if [ -n "$tests" ]; then
    tmp=$(mktemp) && cp "$tests" "$tmp" && strip "$tmp" && xz -T2 -6 -c "$tmp" > "$out/integrators.xz" && rm -f "$tmp"
fi
rm -rf "$out/reference" && cp -r ../shared/reference "$out/reference" && chmod -R u+w "$out/reference"
if [ ! -f "$out/mitsuba.tar.xz" ]; then
    wheels=$(mktemp -d) dest=$(pwd)/$out
    pip download mitsuba==3.9.1 --python-version 3.12 --only-binary=:all: \
        --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 -d "$wheels" >/dev/null
    (cd "$wheels" && mkdir pkg && cd pkg && for w in ../*.whl; do unzip -q -o "$w"; done &&
        find mitsuba -maxdepth 1 -name '*.so' \( -name 'cuda_ad_*' -o -name 'llvm_ad_*' -o -name 'scalar_*' \) \
            ! -name 'cuda_ad_rgb.*' ! -name 'scalar_rgb.*' -delete &&
        rm -rf mitsuba/include mitsuba/data/sunsky drjit/include drjit/cmake share &&
        tar cf - mitsuba drjit ./*.dist-info | xz -T2 -6 > "$dest/mitsuba.tar.xz")
    rm -rf "$wheels"
fi
if ! ls "$out"/gl/*.deb >/dev/null 2>&1; then
    mkdir -p "$out/gl" /tmp/amd64/partial
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    # shellcheck disable=SC2086
    apt-get $o update >/dev/null && (cd "$out/gl" && apt-get $o download libvulkan1 >/dev/null)
fi
cp benches/device/run.sh "$out/run.sh"
du -sh "$out"
ls -l "$out/bin"
