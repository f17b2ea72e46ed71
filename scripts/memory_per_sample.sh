#!/bin/sh
# Peak memory (maximum resident set size) of `gearbif fit` and `gearbif diagnose` on synthetic
# recording sets of growing size; prints the markdown table of docs/tables/memory-per-sample.md.
#
#   sh scripts/memory_per_sample.sh [GEARBIF] [WORKDIR] > docs/tables/memory-per-sample.md
#
# GEARBIF defaults to target/release/gearbif; the sets (`synth --effect none --seed 3` with 12
# ring-downs and 8 driven runs of TURNS input turns at 50 samples per turn) go to WORKDIR (default
# a fresh temporary folder, removed at the end). Needs GNU time (/usr/bin/time -v).
set -eu
BIN=${1:-target/release/gearbif}
WORK=${2:-$(mktemp -d)}
FIT_TURNS=${FIT_TURNS:-"80 320 1280 2500"}
DIAG_TURNS=${DIAG_TURNS:-"80 320 1280"}

peak_kb() { sed -n 's/.*Maximum resident set size (kbytes): //p' "$1"; }
samples() { cat "$1"/*.csv | grep -c '^[0-9-]'; }

echo "| command | input turns per driven run | samples | CSV bytes | peak RSS [MB] |"
echo "|---|---|---|---|---|"
for turns in $FIT_TURNS; do
    set_dir="$WORK/set-$turns"
    [ -d "$set_dir" ] || "$BIN" synth --effect none --seed 3 --turns "$turns" --out "$set_dir" 2>/dev/null
    n=$(samples "$set_dir")
    bytes=$(cat "$set_dir"/*.csv | wc -c)
    /usr/bin/time -v "$BIN" fit "$set_dir" >/dev/null 2>"$WORK/fit-$turns.time"
    echo "| fit | $turns | $n | $bytes | $(( $(peak_kb "$WORK/fit-$turns.time") / 1000 )) |"
    case " $DIAG_TURNS " in
    *" $turns "*)
        /usr/bin/time -v "$BIN" diagnose "$set_dir" --out "$WORK/diag-$turns" --no-figures \
            >/dev/null 2>"$WORK/diag-$turns.time"
        echo "| diagnose --no-figures | $turns | $n | $bytes | $(( $(peak_kb "$WORK/diag-$turns.time") / 1000 )) |"
        ;;
    esac
done
[ -n "${2:-}" ] || rm -rf "$WORK"
