#!/usr/bin/env python3
"""Checks that the modules include one another in one direction only (docs/design.md §1).

Every top-level folder holding C++ files is a module and sits in one layer of LAYERS. A file in a
module may include its own module's headers and those of modules in LOWER layers; a header of the
same layer (a sibling) or of a higher one is an error, printed as FILE:LINE: the include and the
two layers. A folder that holds C++ files but is in no layer is an error too, so that a new module
is placed on purpose.

  check_layers.py [--root DIR]   check the tree (default: the repository holding this script)
  check_layers.py --self-test    check that an upward include in a scratch tree is reported

Run by CTest as Layers.IncludesPointDown and Layers.CheckerCatchesAnUpwardInclude (label layers).
"""

import argparse
import pathlib
import re
import sys
import tempfile

# Lowest first; the order follows target_link_libraries in each module's CMakeLists.txt.
LAYERS = [
    ["core"],                                  # header-only: units, the stopwatch
    ["registration", "dem", "terrain", "graph"],  # the matcher; the maps; terrain layers; pose graph
    ["io", "stereo"],                          # files and formats; correlation stereo
    ["eval", "sim", "mosaic", "campaign"],     # metrics, simulator, mosaics, campaigns
    ["mapper"],                                # the per-frame pipeline
    ["service"],                               # the daemon and outputs around the pipeline
    ["config"],                                # YAML into every module's options struct
    ["apps", "python"],                        # the command and the Python module
    ["tests"],                                 # GoogleTest and its support (may include all)
    ["bench"],                                 # benchmarks (use tests/support)
]

SOURCE_SUFFIXES = {".cpp", ".hpp", ".cc", ".h"}
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([A-Za-z0-9_]+)/[^>"]*[>"]')
SKIPPED = {".git", "datasets", "docs"}


def LayerOf():
    layer = {}
    for index, modules in enumerate(LAYERS):
        for module in modules:
            layer[module] = index
    return layer


def SourceFolders(root):
    """Top-level folders holding C++ files (build trees, whose names start with build, aside)."""
    folders = []
    for child in sorted(root.iterdir()):
        if not child.is_dir() or child.name in SKIPPED or child.name.startswith((".", "build")):
            continue
        if any(p.suffix in SOURCE_SUFFIXES for p in child.rglob("*") if p.is_file()):
            folders.append(child.name)
    return folders


def Check(root):
    """Returns the error lines for the tree at `root`."""
    layer = LayerOf()
    errors = []
    for module in SourceFolders(root):
        if module not in layer:
            errors.append(f"{module}/: holds C++ files but is in no layer of "
                          f"tests/layers/check_layers.py (add it where its links put it)")
            continue
        for path in sorted((root / module).rglob("*")):
            if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
                continue
            text = path.read_text(encoding="utf-8", errors="replace")
            for number, line in enumerate(text.splitlines(), start=1):
                match = INCLUDE.match(line)
                if not match:
                    continue
                target = match.group(1)
                if target == module or target not in layer:
                    continue  # its own module, or a system or third-party header
                if layer[target] < layer[module]:
                    continue
                where = "the same layer as" if layer[target] == layer[module] else "above"
                errors.append(f"{path.relative_to(root)}:{number}: {line.strip()}: {target}/ "
                              f"(layer {layer[target]}) is {where} {module}/ "
                              f"(layer {layer[module]})")
    return errors


def SelfTest():
    """An upward and a sibling include are reported, a downward one is not."""
    with tempfile.TemporaryDirectory() as scratch:
        root = pathlib.Path(scratch)
        (root / "io").mkdir()
        (root / "io" / "A.hpp").write_text('#include "registration/Icp.hpp"\n'
                                           '#include <vector>\n'
                                           '#include "config/Config.hpp"\n')
        (root / "stereo").mkdir()
        (root / "stereo" / "B.cpp").write_text('// x\n#include "io/A.hpp"\n')
        errors = Check(root)
        layer = LayerOf()
        expected = [
            f'io/A.hpp:3: #include "config/Config.hpp": config/ (layer {layer["config"]}) is '
            f'above io/ (layer {layer["io"]})',
            f'stereo/B.cpp:2: #include "io/A.hpp": io/ (layer {layer["io"]}) is the same layer '
            f'as stereo/ (layer {layer["stereo"]})',
        ]
        (root / "newmodule").mkdir()
        (root / "newmodule" / "C.cpp").write_text("")
        unplaced = Check(root)
    if errors != expected or not any(e.startswith("newmodule/:") for e in unplaced):
        print("self-test failed; got:", *errors, *unplaced, sep="\n  ")
        return 1
    print("self-test passed: upward, sibling and unplaced modules are reported")
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=pathlib.Path,
                        default=pathlib.Path(__file__).resolve().parents[2])
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return SelfTest()
    errors = Check(args.root)
    for error in errors:
        print(error)
    if errors:
        print(f"{len(errors)} include(s) against the layer order (docs/design.md §1)")
        return 1
    print("every include points down: " + " < ".join("/".join(m) for m in LAYERS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
