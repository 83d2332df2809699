#!/usr/bin/env bash
# build_failed.sh LOG DIR: prints what a failed build said -- its error lines, then its last lines (a linker
# that ran out of disk or memory says so without the word "error") -- and the free disk and memory beside it.
log="$1" dir="$2"
echo "build failed; its log is $log"
grep -E "error|Error" "$log" | head -n 40
echo "-- the log's last lines:"
tail -n 25 "$log"
echo "-- free disk and memory:"
df -h "$dir"
free -m
exit 0
