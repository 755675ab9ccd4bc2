#!/usr/bin/env bash
# A compiler and linker launcher (CMAKE_CXX_COMPILER_LAUNCHER, CMAKE_CXX_LINKER_LAUNCHER) for
# bench/build_times.sh: runs the command and appends one line to $MBSGEN_BUILD_TIMES,
#   <wall seconds> TAB <compile|link> TAB <output file>
# The command runs as given (no shell in between); its exit status is passed on.
set -u
out=""
prev=""
kind=link
for a in "$@"; do
  [ "$prev" = "-o" ] && out="$a"
  [ "$a" = "-c" ] && kind=compile
  prev="$a"
done
start=$(date +%s.%N)
"$@"
status=$?
end=$(date +%s.%N)
if [ -n "${MBSGEN_BUILD_TIMES:-}" ]; then
  awk -v a="$start" -v b="$end" -v k="$kind" -v o="$out" 'BEGIN { printf "%.2f\t%s\t%s\n", b - a, k, o }' \
    >> "$MBSGEN_BUILD_TIMES"
fi
exit $status
