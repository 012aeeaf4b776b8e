#!/usr/bin/env python3
"""Check that the library's includes point down its layers, and that only mesh/io touches files.

    python3 scripts/check_layers.py [ROOT]

ROOT is a checkout (default: this script's). Each folder under ROOT/src is a layer of the table
below; a source file may include its own folder's headers and those of folders on lower rows,
never a folder on its own row or a higher one (folders on one row stay independent). File
streams (<fstream>, fopen) belong to src/mesh/io only, and examples, bench and
tests (except tests/internal) include no header of src/, only <softhap/softhap.h>. Prints
every violation as FILE:LINE: message and exits 1 if there is any.
"""

import os
import re
import sys

# Lowest first. DESIGN.md's "Layers and folders" draws the same order.
LAYERS = [
    ["core"],
    ["linalg", "mesh", "material", "collision"],
    ["model"],
    ["solver"],
    ["contact"],
    ["world"],
    ["haptic", "cut"],
    ["capi"],
]
RANK = {folder: rank for rank, row in enumerate(LAYERS) for folder in row}
FILE_IO_FOLDER = "mesh/io"
SOURCE = re.compile(r"\.(c|cc|cpp|h|hpp)$")
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
FILE_IO = re.compile(r"#\s*include\s*<fstream>|\b(fopen|freopen|tmpfile)\s*\(|\b(std::)?[io]?fstream\b")


def sources(top):
    for folder, _, files in os.walk(top):
        for name in sorted(files):
            if SOURCE.search(name):
                yield os.path.join(folder, name)


def numbered_lines(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        yield from enumerate(f, 1)


def library_violations(root):
    """Includes in src/ that run sideways or up, and file streams outside mesh/io."""
    src = os.path.join(root, "src")
    for path in sources(src):
        rel = os.path.relpath(path, src).replace(os.sep, "/")
        folder = rel.split("/")[0]
        if folder not in RANK:
            yield path, 1, "folder src/%s is not in the layer table (scripts/check_layers.py)" % folder
            continue
        for number, line in numbered_lines(path):
            match = INCLUDE.match(line)
            if match:
                target = match.group(1).split("/")[0]
                if target != folder and target in RANK and RANK[target] >= RANK[folder]:
                    side = "its own row" if RANK[target] == RANK[folder] else "a higher layer"
                    yield path, number, '%s includes "%s": %s is on %s' % (folder, match.group(1), target, side)
            if FILE_IO.search(line) and not rel.startswith(FILE_IO_FOLDER + "/"):
                yield path, number, "file I/O outside src/%s: %s" % (FILE_IO_FOLDER, line.strip())


def client_violations(root):
    """Examples, bench and tests that reach into src/ instead of the public header."""
    for top in ("examples", "bench", "tests"):
        for path in sources(os.path.join(root, top)):
            if os.path.relpath(path, root).replace(os.sep, "/").startswith("tests/internal/"):
                continue
            for number, line in numbered_lines(path):
                match = INCLUDE.match(line)
                if match and match.group(1).split("/")[0] in RANK:
                    yield path, number, 'includes library internals "%s"' % match.group(1)


def main(root):
    found = list(library_violations(root)) + list(client_violations(root))
    for path, number, message in found:
        print("%s:%d: %s" % (os.path.relpath(path, root), number, message))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
