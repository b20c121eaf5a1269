#!/usr/bin/env bash
# A check of a GPU server in one command, from a prebuilt release binary (no Rust toolchain, no
# network, no Python): lists the Vulkan devices, renders the four shared Cornell scenes on the
# GPU and on the CPU backend, compares the two backends' images, and measures each backend's
# time to a fixed error against the shared references. Prints one table (Markdown, also written
# to OUT/table.md). Finishes within about 8 minutes: each (scene, backend) gets at most --cap
# seconds (default 45; 4 scenes x 2 backends x 45 s = 6 min, plus set-up).
#
#   benches/gpu_check.sh [--photonix PATH] [--references DIR] [--target-error E] [--cap SECONDS]
#                        [--resolution WxH] [--out DIR] [--scenes "box caustics fog glossy"]
#
# Defaults: target/release/photonix, ../shared/reference (from the repository root; each scene's
# reference.exr), E = 0.001 (relMSE as `photonix diff` prints it; the first default, 0.01, is
# reached in one to four passes on an H200 and tells little), the scenes' own resolution
# (256x256). Copy the binary, scenes/ and the references to the server; run from the copy's root.
#
# Time to error: the render runs as a whole command (process start, scene preparation, device
# set-up and kernel compilation, photons, passes, writing) with 1, 2, 4, 8, ... passes until its
# relMSE against the reference is at most E; the table gives the first such run's passes and
# wall time. The doubling stops when the next run would pass the cap (it is predicted to take
# twice the last), and then says "not reached" with the best error. The GPU-vs-CPU column is the
# relMSE between the two backends' images at the same passes (the largest count both rendered):
# they draw the same random numbers, so it should be tiny (float rounding), far below E.
set -euo pipefail
cd "$(dirname "$0")/.."

photonix=target/release/photonix references=../shared/reference target=0.001 cap=45 resolution="" out=""
scenes="box caustics fog glossy"
while [ $# -gt 0 ]; do
    case "$1" in
        --photonix) photonix="$2"; shift 2 ;;
        --references) references="$2"; shift 2 ;;
        --target-error) target="$2"; shift 2 ;;
        --cap) cap="$2"; shift 2 ;;
        --resolution) resolution="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        --scenes) scenes="$2"; shift 2 ;;
        -h|--help) sed -n '9,10p' "$0" | sed 's/^# //'; exit 0 ;;
        *) echo "gpu_check: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
[ -x "$photonix" ] || { echo "gpu_check: no photonix binary at $photonix (give --photonix PATH)" >&2; exit 1; }
for s in $scenes; do
    [ -f "scenes/cornell-$s.toml" ] || { echo "gpu_check: no scenes/cornell-$s.toml" >&2; exit 1; }
    [ -f "$references/cornell-$s/reference.exr" ] || {
        echo "gpu_check: no reference $references/cornell-$s/reference.exr (give --references DIR)" >&2; exit 1; }
done
out="${out:-$(mktemp -d /tmp/gpu_check.XXXXXX)}"
mkdir -p "$out"
size=()
[ -z "$resolution" ] || size=(--resolution "$resolution")

now() { date +%s.%N; }
calc() { awk "BEGIN { print $* }"; }
relmse() { "$photonix" diff "$1" "$2" 2>/dev/null | awk '/^relMSE/ { print $2 }'; }

echo "== photonix devices"
"$photonix" devices | tee "$out/devices.txt"
device=$(sed -n '1s/^0: //p' "$out/devices.txt")
echo

# One (scene, backend): the doubling runs. Sets reached_* and best_* and leaves each run's image
# as $out/<scene>-<backend>-<passes>.exr.
run_backend() {
    local scene=$1 backend=$2 passes=1 spent=0 last=0
    reached_passes="" reached_seconds="" reached_error="" best_error="" best_passes=0 used_device=""
    while true; do
        local image="$out/$scene-$backend-$passes.exr" log="$out/$scene-$backend-$passes.log" t0 t1 seconds error
        t0=$(now)
        if ! "$photonix" render "scenes/cornell-$scene.toml" --backend "$backend" --passes "$passes" "${size[@]}" \
            -o "$image" 2>"$log"; then
            echo "gpu_check: $scene on $backend failed at $passes passes:" >&2
            tail -n 5 "$log" >&2
            return 1
        fi
        t1=$(now)
        seconds=$(calc "$t1 - $t0")
        error=$(relmse "$image" "$references/cornell-$scene/reference.exr")
        used_device=$(grep -o ' on .* -> ' "$log" | head -n 1 | sed 's/^ on //; s/ -> $//')
        best_error=$error best_passes=$passes
        printf '  %-9s %-3s %4d passes %8.2f s  relMSE %s\n' "$scene" "$backend" "$passes" "$seconds" "$error"
        spent=$(calc "$spent + $seconds")
        last=$seconds
        if [ "$(calc "$error <= $target")" = 1 ]; then
            reached_passes=$passes reached_seconds=$seconds reached_error=$error
            return 0
        fi
        # The next run, twice the passes, takes about twice as long.
        [ "$(calc "$spent + 2 * $last <= $cap")" = 1 ] || return 0
        passes=$((passes * 2))
    done
}

rows=()
for scene in $scenes; do
    echo "== cornell-$scene"
    declare -A most=()
    for backend in gpu cpu; do
        run_backend "$scene" "$backend" || { rows+=("| cornell-$scene | $backend | failed (see $out) | | | | |"); continue; }
        most[$backend]=$best_passes
        if [ -n "$reached_passes" ]; then
            result="$reached_passes | $(printf %.2f "$reached_seconds") | $reached_error"
        else
            result="not reached | > $cap (cap) | best $best_error at $best_passes passes"
        fi
        rows+=("| cornell-$scene | $backend | $used_device | $result | @GPUCPU-$scene@ |")
    done
    # GPU against CPU at the largest pass count both rendered
    comparison="n/a"
    if [ -n "${most[gpu]:-}" ] && [ -n "${most[cpu]:-}" ]; then
        common=$(( most[gpu] < most[cpu] ? most[gpu] : most[cpu] ))
        comparison="$(relmse "$out/$scene-gpu-$common.exr" "$out/$scene-cpu-$common.exr") ($common passes)"
    fi
    for i in "${!rows[@]}"; do rows[i]=${rows[i]//@GPUCPU-$scene@/$comparison}; done
    unset most
    echo
done

{
    echo "photonix gpu_check: $(date -u '+%Y-%m-%d %H:%M UTC') on $(hostname), $(nproc) CPUs; first Vulkan device: ${device:-none}"
    echo "time to relMSE <= $target against the shared references (whole command, doubling passes, cap $cap s per row)${resolution:+, at $resolution}"
    echo
    echo "| scene | backend | device | passes to error | seconds | relMSE | GPU vs CPU relMSE (same passes) |"
    echo "| --- | --- | --- | --- | --- | --- | --- |"
    printf '%s\n' "${rows[@]}"
} | tee "$out/table.md"
echo
echo "images, logs and table.md in $out"
