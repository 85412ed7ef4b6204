#!/usr/bin/env python3
"""Every `roslaunch handeye_covariance ...` line of README.md and docs/ as a user types it:
the launch file exists, every argument the line passes is one the file declares (roslaunch
itself ignores an unknown one: a renamed argument would go unnoticed), and roslaunch
resolves the whole tree with them (`roslaunch --dump-params`: includes, $(eval ...) and the
files the launch files read). A line whose arguments end in "..." is a sketch and only its
named arguments are checked. $PWD is a scratch directory holding a board.yaml (the ChArUco
target), as after the README's `handeye target` step.

Usage: check_launch_lines.py REPO  (with the workspace sourced)"""
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

LINE = re.compile(r"roslaunch handeye_covariance (\S+\.launch)((?:[ \t]+[^\s`#]+)*)")


def commands(text):
    """The roslaunch lines of a Markdown text, continuation lines joined."""
    joined = re.sub(r"\\\n\s*", " ", text)
    for match in LINE.finditer(joined):
        yield match.group(1), shlex.split(match.group(2)) if match.group(2).strip() else []


def declared_args(launch_file):
    root = ET.parse(launch_file).getroot()
    return {arg.get("name") for arg in root.findall("arg")}


def main(repo):
    repo = pathlib.Path(repo)
    scratch = pathlib.Path(tempfile.mkdtemp(prefix="launch_lines_"))
    shutil.copy(repo / "config/targets/charuco.yaml", scratch / "board.yaml")
    home = pathlib.Path.home()
    failures, checked = [], 0
    for doc in [repo / "README.md", *sorted((repo / "docs").glob("*.md"))]:
        for launch, args in commands(doc.read_text()):
            where = f"{doc.relative_to(repo)}: roslaunch handeye_covariance {launch} {' '.join(args)}"
            path = repo / "launch" / launch
            if not path.exists():
                failures.append(f"{where}: no launch/{launch}")
                continue
            sketch = any(a == "..." or a.endswith("...") for a in args)
            args = [a.replace("$PWD", str(scratch)).replace("$HOME", str(home)) for a in args if ":=" in a]
            unknown = sorted({a.split(":=")[0] for a in args} - declared_args(path))
            if unknown:
                failures.append(f"{where}: {launch} declares no argument {', '.join(unknown)}")
                continue
            checked += 1
            if sketch:
                continue
            run = subprocess.run(["roslaunch", "--dump-params", "handeye_covariance", launch, *args],
                                 capture_output=True, text=True, cwd=scratch, timeout=60)
            if run.returncode != 0:
                failures.append(f"{where}: roslaunch --dump-params failed:\n{run.stdout}{run.stderr}")
    shutil.rmtree(scratch)
    for failure in failures:
        print(failure)
    if checked == 0:
        print("no roslaunch line found in README.md or docs/")
        return 1
    print(f"{checked} roslaunch lines checked, {len(failures)} wrong")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
