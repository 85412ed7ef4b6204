#!/usr/bin/env python3
"""Every relative link and #anchor in README.md, BENCHMARKS.md and docs/ resolves.

Anchors are GitHub's heading slugs (lower case; letters, digits, spaces, '-' and '_'
kept; spaces to '-'; a repeated heading gets -1, -2, ...). Links inside code blocks
are not links. Exit 1 with one line per broken link.
"""
import glob
import os
import re
import sys
import unicodedata



def slug(heading):
    kept = [c for c in heading.strip().lower() if c in " -_" or unicodedata.category(c)[0] in "LMN"]
    return "".join(kept).replace(" ", "-")


def anchors(path):
    found, seen, fence = set(), {}, False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            fence = not fence
            continue
        m = None if fence else re.match(r"^#{1,6} (.*)", line)
        if m:
            s = slug(m.group(1))
            n = seen.get(s, 0)
            seen[s] = n + 1
            found.add(s if n == 0 else f"{s}-{n}")
    return found


def main(root):
    files = [os.path.join(root, f) for f in ("README.md", "BENCHMARKS.md")]
    files += sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True))
    broken = 0
    for f in files:
        if not os.path.exists(f):
            continue
        text = re.sub(r"```.*?```", "", open(f, encoding="utf-8").read(), flags=re.S)
        for m in re.finditer(r"\]\(([^)\s]+)\)", text):
            target = m.group(1)
            if re.match(r"[a-z]+:", target):
                continue
            path, _, frag = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
            if not os.path.exists(dest):
                print(f"{os.path.relpath(f, root)}: no file {target}")
                broken += 1
                continue
            if frag and dest.endswith(".md") and frag not in anchors(dest):
                print(f"{os.path.relpath(f, root)}: no anchor {target}")
                broken += 1
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")))
