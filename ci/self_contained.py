#!/usr/bin/env python3
"""Fails when a tracked file of the repository refers to a path outside it.

A user has the clone and nothing beside it, so no file may read or name a sibling folder or a path
of the build machine. Checked in every tracked text file:

- a path built on the parent of the repository's root (`ROOT.parent / "x"`,
  `os.path.dirname(REPO)`, `CARGO_MANIFEST_DIR` then `.parent()`) or a `".."` joined as a
  component (`join("..")`, `/ ".."`): the checker names no folder, it catches every way out;
- relative paths that climb out: every `../…` is resolved against the file's own folder and against
  the repository's root (where scripts and tests run), and must land inside the repository, on a
  folder or file it has, under one of the two;
- a path glued onto the crate's root that climbs out (`CARGO_MANIFEST_DIR` followed by "/..");
- absolute paths into home or work folders of a machine (`/work/`, `/home/`, `/root/`, `/tmp/…`
  is allowed: scratch space of the running process).

Usage: ci/self_contained.py [REPO]   (default: the repository this script lives in)
Prints each finding as path:line: text, and exits 1 if there is any.
       ci/self_contained.py --drop DIR   (ci/fuzz.sh, after minimizing a corpus: deletes each file
                                         of DIR the check would refuse, such as fuzz inputs whose
                                         bytes spell `../..`, and says how many)
"""
import os
import re
import subprocess
import sys

# the repository's root as scripts and tests name it (ROOT, REPO, repo_root, …), then its parent
ROOT_PARENT = re.compile(
    r"\b\w*(?:root|repo)\w*\s*\.parent\b"
    r"|dirname\(\s*\w*(?:root|repo)\w*\s*\)"
    r"|CARGO_MANIFEST_DIR.*\.parent\(\)",
    re.IGNORECASE,
)
DOTDOT_COMPONENT = re.compile(r"(?:join\(|/)\s*[\"']\.\.[\"']")
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


def findings(repo, files=None):
    """Each finding (path, line number, why, text) in `files` (paths relative to `repo`;
    default: every tracked file)."""
    me = os.path.relpath(os.path.realpath(__file__), os.path.realpath(repo))
    # this file and its test name, on purpose, the patterns it looks for
    own = {me, os.path.join("tests", "python", "test_self_contained.py")}
    for rel in tracked_files(repo) if files is None else files:
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
            if ROOT_PARENT.search(line):
                why.append("a path built on the parent of the repository's root")
            if DOTDOT_COMPONENT.search(line):
                why.append("joins '..' as a path component")
            if MANIFEST_CLIMB.search(line):
                why.append("climbs out of the crate's root")
            if ABSOLUTE.search(line):
                why.append("an absolute path of a machine")
            for m in CLIMB.finditer(line):
                target = m.group(1) + m.group(2)
                # inside and there: a climb that lands on nothing of the repository is taken
                # to mean the folder beside it
                if not any(
                    inside(repo, os.path.join(base, target))
                    and os.path.exists(os.path.join(base, m.group(1) + m.group(2).split("/")[0]))
                    for base in (folder, os.path.realpath(repo))
                ):
                    why.append(f"'{target}' leads outside the repository")
            for w in why:
                yield rel, no, w, line.strip()[:160]


def drop_refused(folder):
    """Deletes the files of `folder` that `findings` refuses; returns how many."""
    repo = subprocess.run(
        ["git", "-C", folder, "rev-parse", "--show-toplevel"], check=True, capture_output=True,
        text=True,
    ).stdout.strip()
    rels = [os.path.relpath(os.path.join(folder, f), repo) for f in os.listdir(folder)]
    refused = {rel for rel, *_ in findings(repo, rels)}
    for rel in refused:
        os.remove(os.path.join(repo, rel))
    return len(refused)


def main():
    if sys.argv[1:2] == ["--drop"]:
        folder = sys.argv[2]
        print(f"{folder}: {drop_refused(folder)} file(s) that name paths outside the repository dropped")
        return 0
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    found = list(findings(repo))
    for rel, no, why, text in found:
        print(f"{rel}:{no}: {why}: {text}")
    if found:
        print(f"{len(found)} reference(s) to paths outside the repository", file=sys.stderr)
        return 1
    print(f"self-contained: no tracked file of {os.path.realpath(repo)} refers outside it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
