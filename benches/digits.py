#!/usr/bin/env python3
"""Real 64-d vectors for the constraint rows (issue 34 item 4): the 1,797 8x8
handwritten digits that scikit-learn ships (`sklearn/datasets/data/digits.csv.gz`,
64 pixel intensities 0-16 and the digit), as a hierarchy: root -> the ten digits ->
their images, or flat (`--flat`). `--shifts K` adds, per image, its copies moved by
one pixel in each of the first K of 8 directions (up to 9x the rows: 16,173),
the usual augmentation of this data set, so real-like sets above the
nearest-neighbour search's 8,000 rows. Cosine similarity; weight 1 per image.

    pip download --no-deps scikit-learn -d /tmp/skl && unzip -o /tmp/skl/*.whl \\
        'sklearn/datasets/data/digits.csv.gz' -d /tmp/skl
    python3 benches/digits.py /tmp/skl/sklearn/datasets/data/digits.csv.gz \\
        --shifts 8 --flat --out target/scale/digits16k.json

Standard library only; deterministic.
"""
import argparse
import csv
import gzip
import json

DIRECTIONS = [(0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (-1, -1), (1, -1), (-1, 1)]


def shifted(pixels, dy, dx):
    """The 8x8 image moved by (dy, dx), zeros shifted in."""
    out = [0] * 64
    for y in range(8):
        for x in range(8):
            sy, sx = y - dy, x - dx
            if 0 <= sy < 8 and 0 <= sx < 8:
                out[y * 8 + x] = pixels[sy * 8 + sx]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv_gz", help="sklearn/datasets/data/digits.csv.gz")
    ap.add_argument("--shifts", type=int, default=0, choices=range(9))
    ap.add_argument("--flat", action="store_true", help="no digit level")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    with gzip.open(args.csv_gz, "rt") as f:
        rows = [[int(float(x)) for x in r] for r in csv.reader(f) if r]
    groups = {d: [] for d in range(10)}
    for i, r in enumerate(rows):
        pixels, digit = r[:64], r[64]
        images = [pixels] + [shifted(pixels, dy, dx) for dy, dx in DIRECTIONS[:args.shifts]]
        for k, img in enumerate(images):
            if not any(img):
                continue
            groups[digit].append({"id": f"i{i}s{k}", "name": f"{digit}: {i}/{k}", "weight": 1,
                                  "embeddings": img})
    if args.flat:
        children = [leaf for d in range(10) for leaf in groups[d]]
    else:
        children = [{"id": f"d{d}", "name": str(d), "children": groups[d]} for d in range(10)]
    doc = {"id": "root", "name": "digits", "similarityMeasure": "cosine",
           "weightAttribute": "weight", "children": children}
    with open(args.out, "w") as f:
        json.dump(doc, f, separators=(",", ":"))
    print(f"{args.out}: {sum(len(g) for g in groups.values())} images")


if __name__ == "__main__":
    main()
