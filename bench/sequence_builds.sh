#!/usr/bin/env bash
# Two builds of `mcrecon denoise` over one sequence, back to back, best of N each: frames per
# second of the command a user runs (process start, read, filter, write), e.g. the build before
# a change against the build after it (issue 19, point 4).
#
#   bench/sequence_builds.sh OLD_MCRECON NEW_MCRECON 'DIR/in_####.exr' FRAMES [REPEAT] [-- denoise options]
#
# Each build writes to a temp directory of its own; the options after -- go to both (default: -f bmfr).
set -euo pipefail
old=$1 new=$2 input=$3 frames=$4 repeat=${5:-3}
shift $(( $# >= 5 ? 5 : 4 ))
[[ ${1:-} == -- ]] && shift
opts=("$@")
(( ${#opts[@]} )) || opts=(-f bmfr)
count=$(python3 -c "import sys; a, b = map(int, sys.argv[1].split('-')); print(b - a + 1)" "$frames")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
best() { sort -n | head -1; }
for label in old new; do : > "$out/$label.times"; done
for ((r = 0; r < repeat; ++r)); do
  for label in old new; do
    exe=$old; [[ $label == new ]] && exe=$new
    rm -f "$out"/o_*.exr
    t0=$(date +%s.%N)
    "$exe" denoise "$input" -o "$out/o_####.exr" --frames "$frames" "${opts[@]}" > /dev/null 2>&1
    echo "$(date +%s.%N) - $t0" | bc >> "$out/$label.times"
  done
done
for label in old new; do
  s=$(best < "$out/$label.times")
  printf '%s: %.2f frames/s (best of %d: %.2f s for %d frames)\n' "$label" "$(echo "$count / $s" | bc -l)" "$repeat" "$s" "$count"
done
o=$(best < "$out/old.times") n=$(best < "$out/new.times")
printf 'new / old: %.2fx frames per second\n' "$(echo "$o / $n" | bc -l)"
