#!/usr/bin/env python3
"""Sanitizer reports that fuzz targets survived: those printed by a decoder's child process
(src/lightvol/core/detail/isolated.h), which lightvol turns into an error. A report whose faulting frame is in
lightvol's own sources is still a bug of ours and fails; one inside a third-party library
(Draco, OpenImageIO, OpenMesh and what they call) is contained, and only counted.
  child_reports.py LOG SOURCE_DIR   -> exit 1 if any report is ours
"""
import re
import sys

log_path, source_dir = sys.argv[1], sys.argv[2].rstrip("/") + "/src/"
lines = open(log_path, errors="replace").read().splitlines()
ours, contained = [], 0
# libFuzzer's malloc limit is inherited by the children: a decoder asking for more prints this and
# ends its child (lightvol then reports the decoder's failure).
allocations = sum("ERROR: libFuzzer: out-of-memory (malloc(" in line for line in lines)
# Frames of the sanitizer runtimes and libc that sit above the faulting code in a report.
runtime = re.compile(r"(compiler-rt|sanitizer|asan_|ubsan|libc\.so|libstdc\+\+|__interceptor|libFuzzer|fuzzer::)")
i = 0
while i < len(lines):
    line = lines[i]
    if ": runtime error: " in line:  # UBSan: the faulting location leads the line
        if line.startswith(source_dir):
            ours.append(line)
        else:
            contained += 1
    elif re.search(r"ERROR: AddressSanitizer: ", line):
        frame = None
        j = i + 1
        while j < len(lines) and j < i + 80:
            m = re.match(r"\s+#\d+ 0x[0-9a-f]+ in (.*)", lines[j])
            if m and not runtime.search(m.group(1)):
                frame = m.group(1)
                break
            j += 1
        if frame and source_dir in frame:
            ours.append(line.strip() + " at " + frame)
        else:
            contained += 1
        i = j
    i += 1
for report in ours:
    print("sanitizer report in lightvol's code inside a child process: " + report)
if contained:
    print(f"{contained} sanitizer report(s) inside third-party decoders, contained in their child processes")
if allocations:
    print(f"{allocations} allocation(s) beyond -malloc_limit_mb, each ending a decoder's child process")
sys.exit(1 if ours else 0)
