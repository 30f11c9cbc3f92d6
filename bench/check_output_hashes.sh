#!/usr/bin/env bash
# Compares every filter's output hashes (build/bin/mcrecon_output_hashes) with the ones
# recorded in bench/output_hashes/<isa>.txt, where <isa> is the instruction set the
# run uses (MCRECON_ISA, else the best this CPU has: the first line the program prints).
#   bash bench/check_output_hashes.sh            compare (exit 1 on any difference)
#   bash bench/check_output_hashes.sh --record   write the file for this machine's ISA
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BUILD_DIR:-build}/bin/mcrecon_output_hashes
out=$(mktemp)
trap 'rm -f "$out"' EXIT
"$BIN" --threads "${THREADS:-0}" >"$out"
isa=$(head -1 "$out" | sed -n 's/^isa //p')
ref=bench/output_hashes/${isa:-unknown}.txt
if [ "${1:-}" = "--record" ]; then
  mkdir -p bench/output_hashes
  cp "$out" "$ref"
  echo "recorded $(wc -l <"$ref") lines in $ref"
  exit 0
fi
[ -f "$ref" ] || { echo "no recorded hashes for isa '$isa' ($ref)"; exit 2; }
if diff -u "$ref" "$out"; then
  echo "all $(wc -l <"$ref") output hashes match $ref"
else
  echo "output hashes differ from $ref (lines above)"
  exit 1
fi
