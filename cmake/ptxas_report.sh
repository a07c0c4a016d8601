#!/bin/sh
# CUDA compiler launcher (CMake's CUDA_COMPILER_LAUNCHER): runs the compile given after the first
# argument and writes ptxas's per-kernel resource report (-Xptxas=-v: registers, stack frame,
# spill stores and loads) to the file named by the first argument, keeping it out of the build
# log; every other line (warnings, errors) still goes to the log. The report is the compile's own
# output, so the kernels it describes are the ones shipped (tests/test_cuda.py reads it).
report="$1"
shift
"$@" 2> "$report.tmp"
status=$?
grep -v -E '^ptxas info|^ +[0-9]+ bytes stack frame' "$report.tmp" >&2
if [ "$status" -eq 0 ]; then
  mv "$report.tmp" "$report"
else
  rm -f "$report.tmp"
fi
exit "$status"
