#!/usr/bin/env python3
"""Functions over 150 lines in src/ carry a one-line reason above them.

A function is a definition that starts at column 0 (after its doc comment) and ends
at the first `}` at column 0. Its reason is a `// Over 150 lines: ...` line right
above its signature. Prints each function without one and exits 1 when any.
"""
import pathlib
import sys

LIMIT = 150
root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
missing = []
for path in sorted((root / "src").rglob("*.cpp")):
    lines = path.read_text().split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        starts = (line and not line[0].isspace() and "(" in line
                  and not line.startswith(("//", "#", "namespace", "struct", "class", "}", "template", "using", "enum")))
        if not starts or line.rstrip().endswith((";", "}")):
            i += 1
            continue
        j = i
        while j < len(lines) and not lines[j].rstrip().endswith(("{", ";")):
            j += 1
        if j >= len(lines) or lines[j].rstrip().endswith(";"):
            i = j + 1
            continue
        k = j + 1
        while k < len(lines) and lines[k] != "}":
            k += 1
        length = k - i + 1
        if length > LIMIT and not (i > 0 and lines[i - 1].startswith("// Over 150 lines: ")):
            missing.append(f"{path.relative_to(root)}:{i + 1}: {length} lines, no `// Over 150 lines: <why>` above: {line[:80]}")
        i = k + 1
for m in missing:
    print(m)
sys.exit(1 if missing else 0)
