#!/bin/sh
# POV-Ray 3.7's example scenes (Debian's povray-examples) through Photonix: the share that
# imports (`photonix convert`) and, with --render, renders at 160x120 without error, per folder.
# Not in CI (minutes). Needs: apt-get install povray-examples povray-includes.
#   benches/pov_examples.sh [--render] [PHOTONIX_BINARY]
# Writes one line per scene to pov_examples.log (scene|error or empty) and prints a table.
set -u
RENDER=0
if [ "${1:-}" = "--render" ]; then RENDER=1; shift; fi
BIN=${1:-target/release/photonix}
EXAMPLES=/usr/share/doc/povray/examples
[ -d "$EXAMPLES" ] || { echo "install povray-examples first (apt-get install povray-examples povray-includes)"; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
LOG=pov_examples.log
: > "$LOG"
find "$EXAMPLES" -name '*.pov' | sort | while read -r f; do
    if [ "$RENDER" = 1 ]; then
        # Few photons and one pass of one sample: this checks that the scene runs, not its look.
        err=$(timeout 120 "$BIN" render "$f" --backend cpu --resolution 160x120 --spp 1 --passes 1 \
              --photons 2000 --caustic-photons 2000 -o "$TMP/x.png" 2>&1 >/dev/null | grep '^error' | head -1)
        rc=$?
        [ -z "$err" ] && [ ! -s "$TMP/x.png" ] && err="error: no image (timeout or crash)"
        rm -f "$TMP/x.png"
    else
        err=$(timeout 60 "$BIN" convert "$f" -o "$TMP/x.toml" --resolution 160x120 2>&1 | grep '^error' | head -1)
    fi
    echo "$f|$err" >> "$LOG"
done
# Per folder: scenes, successes, share.
awk -F'|' -v ex="$EXAMPLES/" '{
    p = $1; sub(ex, "", p); n = split(p, parts, "/"); d = (n > 1) ? parts[1] : ".";
    total[d]++; all++; if ($2 == "") { ok[d]++; good++ }
} END {
    for (d in total) printf "| %s | %d | %d | %.0f%% |\n", d, total[d], ok[d], 100 * ok[d] / total[d];
    printf "| zz all | %d | %d | %.1f%% |\n", all, good, 100 * good / all;
}' "$LOG" | sort | sed 's/^| zz all/| **all**/' > "$TMP/rows"
printf '| folder | scenes | ok | share |\n| --- | --- | --- | --- |\n'
cat "$TMP/rows"
# The most frequent reasons, for the refusals.
echo
grep -v '|$' "$LOG" | sed 's/^[^|]*|error: [^ ]* //; s/ (in the scene as translated.*//' | sort | uniq -c | sort -rn | head -15
