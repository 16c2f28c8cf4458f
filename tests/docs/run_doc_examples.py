#!/usr/bin/env python3
"""Runs the examples of README.md and docs/*.md, so that the documentation cannot rot.

A fenced block whose info string is `sh runnable` or `python runnable` is an example a user can
run on the bundled data. The blocks of one page run in order in one scratch folder, where
`datasets` is a symlink to the repository's datasets/ and `rovermap` is on PATH: sh blocks with
`bash -euo pipefail`, python blocks with the build's Python module on PYTHONPATH. A line
`# expect: RELATIVE/PATH` in a block names a file (or folder) the block promises; it must exist
once the block has run. A block that exits non-zero, or leaves a promised file missing, fails
the page, naming the page, the block's first line and its output.

--check-links checks instead that every relative link of the pages resolves: the file or folder
exists in the source tree and, for a link to a Markdown page with #anchor, that page has a
heading with that anchor (GitHub's rule).

Standard library only.
"""
import argparse
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

RUNNABLE = {"sh runnable": "sh", "python runnable": "python"}
FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`]*?)\s*$")
EXPECT = re.compile(r"^\s*#\s*expect:\s*(?P<paths>\S.*?)\s*$")
LINK = re.compile(r"(?<!!)\[(?P<text>[^\]]*)\]\((?P<target>[^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"!\[(?P<text>[^\]]*)\]\((?P<target>[^)\s]+)\)")
OUTPUT_TAIL_LINES = 80


class Block:
    def __init__(self, kind, line, text):
        self.kind = kind    # "sh" or "python"
        self.line = line    # 1-based line of the opening fence
        self.text = text

    def expected_paths(self):
        paths = []
        for text_line in self.text.splitlines():
            match = EXPECT.match(text_line)
            if match:
                paths.extend(match.group("paths").split())
        return paths


def parse_fences(lines):
    """Yields (info, opening line number, body lines, is_closed) for every fenced block."""
    i = 0
    while i < len(lines):
        match = FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        fence = match.group("fence")
        info = match.group("info").strip()
        start = i + 1
        body = []
        i += 1
        closed = False
        while i < len(lines):
            close = FENCE.match(lines[i])
            if (close and close.group("fence")[0] == fence[0]
                    and len(close.group("fence")) >= len(fence) and not close.group("info")):
                closed = True
                break
            body.append(lines[i])
            i += 1
        yield info, start, body, closed
        i += 1


def extract_blocks(page_text):
    blocks = []
    for info, line, body, closed in parse_fences(page_text.splitlines()):
        if not closed:
            raise ValueError(f"line {line}: a code fence that is never closed")
        normalised = " ".join(info.split())
        if normalised in RUNNABLE:
            blocks.append(Block(RUNNABLE[normalised], line, "\n".join(body) + "\n"))
    return blocks


def tail(text, lines=OUTPUT_TAIL_LINES):
    parts = text.rstrip("\n").splitlines()
    if len(parts) <= lines:
        return "\n".join(parts)
    return f"[... {len(parts) - lines} lines cut ...]\n" + "\n".join(parts[-lines:])


def run_page(args, page):
    page_path = (args.source / page).resolve()
    name = os.path.relpath(page_path, args.source)
    try:
        blocks = extract_blocks(page_path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        print(f"{name}: {error}")
        return False
    if not blocks:
        print(f"{name}: no runnable examples")
        return True

    root = pathlib.Path(tempfile.mkdtemp(prefix="rovermap-docs-"))
    work = root / "work"
    bin_dir = root / "bin"
    block_dir = root / "blocks"
    for folder in (work, bin_dir, block_dir):
        folder.mkdir()
    (work / "datasets").symlink_to(args.source / "datasets", target_is_directory=True)
    # A symlink keeps the launcher finding rovermap-full: it reads /proc/self/exe.
    (bin_dir / "rovermap").symlink_to(args.rovermap)

    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env["MPLBACKEND"] = "Agg"  # a plotting example must not wait for a window
    if args.pythonpath:
        env["PYTHONPATH"] = os.pathsep.join(
            [str(args.pythonpath)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))

    ok = True
    for block in blocks:
        where = f"{name}:{block.line}"
        if block.kind == "python" and args.no_python:
            print(f"{where}: python example skipped (this build has no Python module)")
            continue
        script = block_dir / f"line{block.line}.{'sh' if block.kind == 'sh' else 'py'}"
        script.write_text(block.text, encoding="utf-8")
        command = (["bash", "-euo", "pipefail", str(script)] if block.kind == "sh"
                   else [args.python, str(script)])
        try:
            proc = subprocess.run(command, cwd=work, env=env, stdin=subprocess.DEVNULL,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True, errors="replace", timeout=args.timeout)
            status, output = proc.returncode, proc.stdout
        except subprocess.TimeoutExpired as expired:
            status = f"timeout after {args.timeout} s"
            output = expired.stdout if isinstance(expired.stdout, str) else (
                (expired.stdout or b"").decode(errors="replace"))
        if status != 0:
            print(f"{where}: {block.kind} example failed (exit status {status}); its output:")
            print(tail(output))
            ok = False
            break  # later blocks build on this one
        missing = []
        for path in block.expected_paths():
            if os.path.isabs(path) or ".." in pathlib.PurePath(path).parts:
                missing.append(f"{path} (an expected path must be relative to the scratch folder)")
            elif not (work / path).exists():
                missing.append(path)
        if missing:
            print(f"{where}: {block.kind} example did not make " + ", ".join(missing)
                  + "; its output:")
            print(tail(output))
            ok = False
            break
        print(f"{where}: ok ({block.kind}, {len(block.expected_paths())} files checked)")
        if args.verbose and output.strip():
            print(tail(output))

    if ok and not args.keep:
        shutil.rmtree(root, ignore_errors=True)
    else:
        print(f"{name}: scratch folder kept: {work}")
    return ok


def slug(heading):
    """GitHub's anchor for a heading: formatting dropped, lower case, punctuation removed."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = text.replace("`", "").replace("*", "").strip().lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def fenced_line_indices(lines):
    """0-based indices of the lines inside fenced blocks, fences included."""
    in_fence = set()
    for _, start, body, _ in parse_fences(lines):
        in_fence.update(range(start - 1, start + len(body) + 1))
    return in_fence


def anchors_of(page_path):
    anchors = set()
    seen = {}
    lines = page_path.read_text(encoding="utf-8").splitlines()
    in_fence = fenced_line_indices(lines)
    for index, line in enumerate(lines):
        if index in in_fence:
            continue
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not match:
            continue
        anchor = slug(match.group(1))
        count = seen.get(anchor, 0)
        seen[anchor] = count + 1
        anchors.add(anchor if count == 0 else f"{anchor}-{count}")
    return anchors


def check_links(args, pages):
    problems = []
    for page in pages:
        page_path = (args.source / page).resolve()
        name = os.path.relpath(page_path, args.source)
        lines = page_path.read_text(encoding="utf-8").splitlines()
        in_fence = fenced_line_indices(lines)
        for index, line in enumerate(lines):
            if index in in_fence:
                continue
            prose = re.sub(r"`[^`]*`", "", line)  # links in code spans are not links
            for match in list(LINK.finditer(prose)) + list(IMAGE.finditer(prose)):
                target = match.group("target")
                if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):
                    continue  # http:, https:, mailto:
                path_part, _, anchor = target.partition("#")
                resolved = (page_path.parent / path_part).resolve() if path_part else page_path
                relative = os.path.relpath(resolved, args.source)
                where = f"{name}:{index + 1}"
                if relative.startswith(".."):
                    problems.append(f"{where}: {target} leaves the repository")
                    continue
                if not resolved.exists():
                    if relative in args.allow_missing:
                        continue
                    problems.append(f"{where}: {target}: no such file ({relative})")
                    continue
                if anchor and resolved.suffix == ".md" and anchor not in anchors_of(resolved):
                    problems.append(f"{where}: {target}: {relative} has no heading #{anchor}")
    for problem in problems:
        print(problem)
    print(f"links: {len(pages)} pages checked, {len(problems)} broken")
    return not problems


def all_pages(source):
    return ["README.md"] + sorted(
        os.path.relpath(path, source) for path in (source / "docs").glob("*.md"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", required=True, type=pathlib.Path,
                        help="the repository (its datasets/ and the pages)")
    parser.add_argument("--rovermap", type=pathlib.Path, help="the build's rovermap command")
    parser.add_argument("--page", action="append", default=[],
                        help="a page relative to --source (repeatable); default every page")
    parser.add_argument("--pythonpath", type=pathlib.Path,
                        help="the folder holding the built `rovermap` Python package "
                             "(default: python/ of the build that holds --rovermap)")
    parser.add_argument("--python", default=sys.executable,
                        help="the interpreter for python examples (default: this one)")
    parser.add_argument("--no-python", action="store_true",
                        help="skip python examples (a build without the Python module)")
    parser.add_argument("--timeout", type=float, default=300, help="seconds per block")
    parser.add_argument("--keep", action="store_true", help="keep the scratch folders")
    parser.add_argument("--verbose", action="store_true", help="print every block's output")
    parser.add_argument("--check-links", action="store_true",
                        help="check the pages' relative links instead of running examples")
    parser.add_argument("--allow-missing", action="append", default=[],
                        help="a link target (relative to --source) that may be missing")
    args = parser.parse_args()

    args.source = args.source.resolve()
    pages = args.page or all_pages(args.source)
    for page in pages:
        if not (args.source / page).is_file():
            parser.error(f"{page}: no such page under {args.source}")
    if args.check_links:
        return 0 if check_links(args, pages) else 1

    if not args.rovermap:
        parser.error("--rovermap is needed to run the examples")
    args.rovermap = args.rovermap.resolve()
    if not os.access(args.rovermap, os.X_OK):
        parser.error(f"{args.rovermap}: not an executable")
    if args.pythonpath is None and not args.no_python:
        # apps/rovermap in a build tree; the module is in python/rovermap of the same build.
        args.pythonpath = args.rovermap.parent.parent / "python"
    ok = True
    for page in pages:
        ok = run_page(args, page) and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
