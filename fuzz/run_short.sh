#!/bin/sh
# The short fuzz run of ctest: run_short.sh FUZZER WORK_DIR SEED_DIR [libFuzzer flags...]
# WORK_DIR starts empty each time (new inputs go there, the seeds stay as generated) and
# receives any crash input (WORK_DIR/crash-*, leak-*, timeout-*, oom-*).
set -eu
fuzzer=$1 work=$2 seeds=$3
shift 3
rm -rf "$work"
mkdir -p "$work/corpus"
exec "$fuzzer" -artifact_prefix="$work/" -print_final_stats=1 "$@" "$work/corpus" "$seeds"
