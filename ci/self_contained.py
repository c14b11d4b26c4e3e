#!/usr/bin/env python3
"""Fails when a tracked file of the repository refers to a path outside it.

A user has the clone and nothing beside it, so no file may read or name a sibling folder such as
../shared or a path of the build machine. Checked in every tracked text file:

- the names of the original hand-over folder (`../shared`, `shared/data`, `shared/spec`) and a
  path built to it (`.parent / "shared"`);
- relative paths that climb out: every `../…` is resolved against the file's own folder and against
  the repository's root (where scripts and tests run), and must land inside the repository under
  one of the two;
- a path glued onto the crate's root that climbs out (`CARGO_MANIFEST_DIR` followed by "/..");
- absolute paths into home or work folders of a machine (`/work/`, `/home/`, `/root/`, `/tmp/…`
  is allowed: scratch space of the running process).

Usage: ci/self_contained.py [REPO]   (default: the repository this script lives in)
Prints each finding as path:line: text, and exits 1 if there is any.
"""
import os
import re
import subprocess
import sys

NAMED = re.compile(r"\.\./shared|shared/data|shared/spec|parent\s*/\s*[\"']shared[\"']")
CLIMB = re.compile(r"(?<![\w.])((?:\.\./)+)([\w.\-/]*)")
MANIFEST_CLIMB = re.compile(r"CARGO_MANIFEST_DIR[\"')\s,]*[\"']/\.\.")
ABSOLUTE = re.compile(r"(?<![\w.~])/(?:work|home|root)/[\w.\-]")


def tracked_files(repo):
    out = subprocess.run(
        ["git", "-C", repo, "ls-files", "-z"], check=True, capture_output=True
    ).stdout
    return [f for f in out.decode().split("\0") if f]


def inside(repo, path):
    repo = os.path.realpath(repo)
    return os.path.commonpath([repo, os.path.normpath(path)]) == repo


def findings(repo):
    me = os.path.relpath(os.path.realpath(__file__), os.path.realpath(repo))
    # this file and its test name, on purpose, the patterns it looks for
    own = {me, os.path.join("tests", "python", "test_self_contained.py")}
    for rel in tracked_files(repo):
        if rel in own:
            continue
        path = os.path.join(repo, rel)
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except (UnicodeDecodeError, FileNotFoundError, IsADirectoryError):
            continue  # binary (figures) or a path git lists but the tree lacks
        folder = os.path.dirname(os.path.join(os.path.realpath(repo), rel))
        for no, line in enumerate(text.splitlines(), 1):
            why = []
            if NAMED.search(line):
                why.append("names the hand-over folder outside the repository")
            if MANIFEST_CLIMB.search(line):
                why.append("climbs out of the crate's root")
            if ABSOLUTE.search(line):
                why.append("an absolute path of a machine")
            for m in CLIMB.finditer(line):
                target = m.group(1) + m.group(2)
                if not any(
                    inside(repo, os.path.join(base, target))
                    for base in (folder, os.path.realpath(repo))
                ):
                    why.append(f"'{target}' leads outside the repository")
            for w in why:
                yield f"{rel}:{no}: {w}: {line.strip()[:160]}"


def main():
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    found = list(findings(repo))
    for f in found:
        print(f)
    if found:
        print(f"{len(found)} reference(s) to paths outside the repository", file=sys.stderr)
        return 1
    print(f"self-contained: no tracked file of {os.path.realpath(repo)} refers outside it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
