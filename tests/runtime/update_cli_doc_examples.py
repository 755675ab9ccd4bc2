#!/usr/bin/env python3
"""Re-runs the `$ mbsgen linear ...` examples of docs/cli.md and rewrites their outputs in place.

Usage: tests/runtime/update_cli_doc_examples.py BUILD_DIR/runtime/mbsgen-linear
Run from the repository root; the examples run in tests/runtime/data. Review the diff: the test
MbsgenLinearCli.DocumentationExamples compares the documentation with the program's output.
"""
import subprocess
import sys

import os
exe = os.path.abspath(sys.argv[1])
lines = open("docs/cli.md").read().split("\n")
out = []
i = 0
in_console = False
while i < len(lines):
    line = lines[i]
    if line.startswith("```"):
        in_console = line == "```console"
        out.append(line)
        i += 1
        continue
    if in_console and line.startswith("$ mbsgen linear "):
        args = line[len("$ mbsgen linear "):]
        p = subprocess.run(f"'{exe}' {args} 2>&1", shell=True, cwd="tests/runtime/data",
                           capture_output=True, text=True)
        out.append(line)
        out.extend(p.stdout.rstrip("\n").split("\n"))
        if p.returncode != 0:
            out.extend(["$ echo $?", str(p.returncode)])
        i += 1
        while i < len(lines) and not lines[i].startswith("$ mbsgen linear ") and not lines[i].startswith("```"):
            i += 1
        continue
    out.append(line)
    i += 1
open("docs/cli.md", "w").write("\n".join(out))
