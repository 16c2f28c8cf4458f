#!/usr/bin/env python3
"""The fuzz seeds cut from the repository's own files stay equal to them.

Checked (exit 1 naming the first differing seed and what it should be):
- the seeds that are copies of a file (sequence.yaml of the bundled datasets, the presets, a
  ground truth) equal it byte for byte;
- corpus/config/default_SECTION.yaml is SECTION's block of config/default.yaml, one per section;
- corpus/set/default_keys_NN.txt hold every key of config/default.yaml as `key=value` with its
  default, in the file's order, 12 a seed.

`--write` rewrites the seeds from their originals instead (after a change to the defaults, a
preset or a dataset). Run by CTest as Fuzz.CorpusMatchesItsOriginals.
"""
import argparse
import pathlib
import re
import sys

# Seed (under tests/fuzz/corpus) -> the file it is a copy of (under the repository root).
COPIES = {
    "config/preset_fast.yaml": "config/presets/fast.yaml",
    "sequence_yaml/kitti_stereo51.yaml": "datasets/kitti_stereo51/sequence.yaml",
    "sequence_yaml/sim_tiny_cloud.yaml": "datasets/sim_tiny_cloud/sequence.yaml",
    "sequence_yaml/sim_tiny_stereo.yaml": "datasets/sim_tiny_stereo/sequence.yaml",
    "kitti/sim_tiny_cloud_groundtruth.tum": "datasets/sim_tiny_cloud/groundtruth.tum",
}
KEYS_PER_SET_SEED = 12


def sections(default_yaml):
    """{section: its block of lines, header included, up to the blank line after it}."""
    blocks = {}
    current = None
    for line in default_yaml.splitlines(keepends=True):
        header = re.match(r"^([A-Za-z_][A-Za-z0-9_]*):\s*$", line)
        if header:
            current = header.group(1)
            blocks[current] = [line]
        elif current is not None and line.strip():
            blocks[current].append(line)
        else:
            current = None
    return {name: "".join(lines) for name, lines in blocks.items()}


def default_keys(blocks):
    """`section.key=value` of every key, in the file's order."""
    keys = []
    for name, block in blocks.items():
        for line in block.splitlines()[1:]:
            entry = re.match(r"^  ([A-Za-z_][A-Za-z0-9_]*):\s*(.*?)\s*(#.*)?$", line)
            if entry:
                keys.append(f"{name}.{entry.group(1)}={entry.group(2)}")
    return keys


def expected_seeds(root):
    """{seed path relative to the corpus: its expected bytes}, and the generated seed globs."""
    seeds = {seed: (root / original).read_bytes() for seed, original in COPIES.items()}
    blocks = sections((root / "config" / "default.yaml").read_text())
    for name, block in blocks.items():
        seeds[f"config/default_{name}.yaml"] = block.encode()
    keys = default_keys(blocks)
    for n, start in enumerate(range(0, len(keys), KEYS_PER_SET_SEED)):
        chunk = keys[start:start + KEYS_PER_SET_SEED]
        seeds[f"set/default_keys_{n:02d}.txt"] = "".join(k + "\n" for k in chunk).encode()
    return seeds, ["config/default_*.yaml", "set/default_keys_*.txt"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source", required=True, help="the repository root")
    parser.add_argument("--write", action="store_true", help="rewrite the seeds")
    args = parser.parse_args()
    root = pathlib.Path(args.source)
    corpus = root / "tests" / "fuzz" / "corpus"
    seeds, generated = expected_seeds(root)
    # Generated seeds with no original any more (a section or keys removed).
    stale = sorted({p.relative_to(corpus).as_posix() for g in generated for p in corpus.glob(g)} -
                   set(seeds))
    if args.write:
        for seed in stale:
            (corpus / seed).unlink()
        for seed, data in seeds.items():
            if not (corpus / seed).is_file() or (corpus / seed).read_bytes() != data:
                (corpus / seed).write_bytes(data)
                print(f"wrote tests/fuzz/corpus/{seed}")
        return 0
    problems = [f"tests/fuzz/corpus/{seed}: no original any more (remove it)" for seed in stale]
    for seed, data in seeds.items():
        path = corpus / seed
        if not path.is_file():
            problems.append(f"tests/fuzz/corpus/{seed}: missing")
        elif path.read_bytes() != data:
            have = path.read_bytes().decode(errors="replace").splitlines()
            want = data.decode(errors="replace").splitlines()
            line = next((k for k, (a, b) in enumerate(zip(have, want)) if a != b),
                        min(len(have), len(want)))
            problems.append(f"tests/fuzz/corpus/{seed}: differs from its original at line "
                            f"{line + 1}: {want[line] if line < len(want) else '(end)'!r}")
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        print("rewrite them with: tests/fuzz/check_corpus.py --source . --write", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
