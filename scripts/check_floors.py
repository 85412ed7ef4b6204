#!/usr/bin/env python3
"""The package's floors (docs/code_map.md, "Floors"): each folder of include/ and src/
includes only the folders its row allows, no file reaches another folder by a
relative path, and no two units (a header and its source, by stem) include each
other through any chain. Prints each breach and exits 1; silent and 0 when all hold."""
import os
import re
import sys

repo = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def floors():
    """{folder: set of folders it may include} from code_map.md's Floors table."""
    text = open(os.path.join(repo, "docs", "code_map.md"), encoding="utf-8").read()
    section = text.split("## Floors", 1)[1].split("\n## ", 1)[0]
    allowed = {}
    for line in section.splitlines():
        cells = [c.strip(" `") for c in line.strip().strip("|").split("|")]
        if len(cells) < 2 or not re.fullmatch(r"[a-z_]+", cells[0]) or cells[0] == "folder":
            continue
        names = re.sub(r"\([^)]*\)", "", cells[1])  # a row's remarks are in parentheses
        allowed[cells[0]] = {c.strip(" `") for c in names.split(",") if re.fullmatch(r"[a-z_]+", c.strip(" `"))}
    if not allowed:
        sys.exit("docs/code_map.md has no Floors table")
    return allowed


def units():
    """{unit: (folder, path, text)}, a unit being folder/stem of a header or a source."""
    out = {}
    for base, strip in (("include/handeye_covariance", True), ("src", True)):
        root = os.path.join(repo, base)
        for directory, _, files in os.walk(root):
            for name in files:
                if not name.endswith((".h", ".cpp")):
                    continue
                path = os.path.join(directory, name)
                rel = os.path.relpath(path, root)
                unit = os.path.splitext(rel)[0]
                out.setdefault(unit, []).append((rel.split(os.sep)[0], os.path.relpath(path, repo),
                                                open(path, encoding="utf-8").read()))
    return out


def main():
    allowed = floors()
    files = units()
    edges = {u: set() for u in files}
    breaches = []
    for unit, parts in files.items():
        for folder, path, text in parts:
            if folder not in allowed:
                breaches.append(f"{path}: folder `{folder}` has no row in docs/code_map.md's Floors table")
                continue
            for target in INCLUDE.findall(text):
                if target.startswith("../") or "/../" in target:
                    breaches.append(f"{path}: includes {target} by a relative path (include the public header)")
                    continue
                if not target.startswith("handeye_covariance/") or target.count("/") < 2:
                    continue  # not the package's, or a generated message header
                included = os.path.splitext(target[len("handeye_covariance/"):])[0]
                to_folder = included.split("/")[0]
                if to_folder != folder and to_folder not in allowed[folder]:
                    breaches.append(f"{path}: {folder} includes {to_folder} ({target}); its floor allows "
                                    f"{', '.join(sorted(allowed[folder])) or 'nothing of the package'}")
                if included != unit and included in files:
                    edges[unit].add(included)
    # Loops: strongly connected units (Tarjan), iteratively.
    index, low, on_stack, stack, loops, counter = {}, {}, set(), [], [], [0]
    for start in sorted(edges):
        if start in index:
            continue
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter[0]; counter[0] += 1
        stack.append(start); on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]; counter[0] += 1
                    stack.append(child); on_stack.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop(); on_stack.discard(member); component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    loops.append(sorted(component))
    for loop in loops:
        breaches.append("include loop: " + " <-> ".join(loop) + " (a header or source of each includes the next)")
    for b in breaches:
        print(b)
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())
