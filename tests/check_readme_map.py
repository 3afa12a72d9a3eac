#!/usr/bin/python3
"""Every source file is named in its folder's README.

    check_readme_map.py REPOSITORY_ROOT

Walks core/, materials/, contact/, integrators/, apps/, bench/ and tests/ for .cpp, .hpp, .py and
.sh files. Each must be named in the README.md of its folder or, where its folder has none, of
the nearest folder above it that has one (apps/tools/render.py in apps/README.md). A file is
named when the README holds its path relative to the README's folder or its file name
(`tools/render.py`, `render.py`), or, in backticks, that path without its extension
(`gmsh_reader`) or with the other extension of a .hpp/.cpp pair (`mesh.hpp` names mesh.cpp: one
concept per pair). The top-level README.md stays an entry document: at most 300 lines, and
every relative link in any README.md names a file or folder that exists. Prints one line per
problem and exits 1; prints nothing and exits 0 when there is none.
"""

import os
import re
import sys

FOLDERS = ("core", "materials", "contact", "integrators", "apps", "bench", "tests")
EXTENSIONS = (".cpp", ".hpp", ".py", ".sh")
PAIR = {".cpp": ".hpp", ".hpp": ".cpp"}
ENTRY_LINES = 300  # the top-level README.md, read top to bottom by a newcomer


def readme_of(root, folder):
    """The README.md of `folder` or of the nearest folder above it (relative paths)."""
    while True:
        if os.path.isfile(os.path.join(root, folder, "README.md")):
            return folder
        if "/" not in folder:
            return None
        folder = folder.rsplit("/", 1)[0]


def named(text, backticked, relative):
    """Whether the README text names the file at `relative` (to the README's folder)."""
    name = os.path.basename(relative)
    stem, ext = os.path.splitext(relative)
    for candidate in {relative, name}:
        # The whole name, not a part of a longer one (mesh.hpp inside tet_mesh.hpp).
        if re.search(r"(?<![\w./-])" + re.escape(candidate) + r"(?![\w-])", text):
            return True
    forms = {stem, os.path.basename(stem)}
    if ext in PAIR:
        forms |= {f + PAIR[ext] for f in (stem, os.path.basename(stem))}
    return bool(forms & backticked)


def entry_document_problems(root):
    """The top-level README's length and the relative links of every README.md."""
    problems = []
    with open(os.path.join(root, "README.md"), encoding="utf-8") as r:
        lines = r.read().count("\n")
    if lines > ENTRY_LINES:
        problems.append(f"readme_map: README.md has {lines} lines (at most {ENTRY_LINES})")
    readmes = [os.path.join(root, "README.md")]
    for top in FOLDERS:
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs.sort()
            if "README.md" in files:
                readmes.append(os.path.join(folder, "README.md"))
    for readme in readmes:
        with open(readme, encoding="utf-8") as r:
            text = r.read()
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if re.match(r"[a-z]+:", target):
                continue  # a web address
            if not os.path.exists(os.path.join(os.path.dirname(readme), target)):
                rel = os.path.relpath(readme, root)
                problems.append(f"readme_map: {rel} links to {target}, which does not exist")
    return problems


def main():
    if len(sys.argv) != 2:
        print("usage: check_readme_map.py REPOSITORY_ROOT", file=sys.stderr)
        return 2
    root = sys.argv[1]
    missing = []
    for top in FOLDERS:
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs.sort()
            rel_folder = os.path.relpath(folder, root)
            for f in sorted(files):
                if not f.endswith(EXTENSIONS):
                    continue
                path = os.path.join(rel_folder, f)
                owner = readme_of(root, rel_folder)
                if owner is None:
                    missing.append(f"readme_map: {path} has no README.md in its folder or above it")
                    continue
                with open(os.path.join(root, owner, "README.md"), encoding="utf-8") as r:
                    text = r.read()
                backticked = {t.strip().rstrip("/") for t in re.findall(r"`([^`\n]+)`", text)}
                if not named(text, backticked, os.path.relpath(path, owner)):
                    missing.append(f"readme_map: {path} is not named in {owner}/README.md")
    missing += entry_document_problems(root)
    for line in missing:
        print(line)
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
