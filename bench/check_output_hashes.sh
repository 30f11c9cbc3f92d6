#!/usr/bin/env bash
# Compares every filter's output hashes (build/bin/mcrecon_output_hashes) with the ones
# recorded in bench/output_hashes/<isa>.txt, where <isa> is the instruction set the
# run uses (MCRECON_ISA, else the best this CPU has: the first line the program prints).
#   bash bench/check_output_hashes.sh [--scenes a,b] [--filters a,b]   compare (exit 1 on a difference)
#   bash bench/check_output_hashes.sh --record                          write the file for this ISA
# With --scenes / --filters only those lines of the recorded file are compared.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BUILD_DIR:-build}/bin/mcrecon_output_hashes
record=0; scenes=""; filters=""; args=()
while (($#)); do
  case "$1" in
    --record) record=1 ;;
    --scenes) scenes=$2; args+=("$1" "$2"); shift ;;
    --filters) filters=$2; args+=("$1" "$2"); shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
out=$(mktemp); ref_sel=$(mktemp)
trap 'rm -f "$out" "$ref_sel"' EXIT
"$BIN" --threads "${THREADS:-0}" "${args[@]}" >"$out"
isa=$(head -1 "$out" | sed -n 's/^isa //p')
ref=bench/output_hashes/${isa:-unknown}.txt
if ((record)); then
  ((${#args[@]} == 0)) || { echo "--record takes no --scenes/--filters" >&2; exit 2; }
  mkdir -p bench/output_hashes
  cp "$out" "$ref"
  echo "recorded $(wc -l <"$ref") lines in $ref"
  exit 0
fi
[ -f "$ref" ] || { echo "no recorded hashes for isa '$isa' ($ref)"; exit 2; }
awk -v s=",$scenes," -v f=",$filters," 'NR == 1 || ((s == ",," || index(s, "," $1 ",")) && (f == ",," || index(f, "," $2 ",")))' \
  "$ref" >"$ref_sel"
if diff -u "$ref_sel" "$out"; then
  echo "all $(wc -l <"$ref_sel") output hashes match $ref"
else
  echo "output hashes differ from $ref (lines above)"
  exit 1
fi
