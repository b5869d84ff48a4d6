#!/usr/bin/env python3
"""What each part of hattr's lossless sample encoding (hsc2, docs/study-store.md) gains, measured
on a study's own trials: the size ratio (raw doubles / encoded bytes, over the trials measured)
as the parts are added one at a time, from the first revision (hsc1) to the whole of hsc2.

    PYTHONPATH=build/release/python python3 bench/sample_codec_parts.py --db study.sqlite [--every 11] [--json]

The trials are read through hattr's Python module (either encoding, any schema-4 study). The
steps are written here again in numpy, from the description in docs/study-store.md, and the
sizes are zstd's (python3-zstandard, level 1) plus the packed bits; the headers (a few hundred
bytes a trial) are left out. This script does not decode what it sizes: the C++ codec is the
one that is tested bit for bit (tests/io/sample_codec_test.cpp), and `bench_sample_codec --db`
gives its own ratio on the same study. Needs Debian's python3-numpy and python3-zstandard."""

import argparse
import json
import sys
from math import comb

import numpy as np
import zstandard

import hattr

STORED = ["t", "x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz", "cmd_fx", "cmd_fy", "cmd_fz",
          "guide_fx", "guide_fy", "guide_fz", "contact", "pen_down", "pressure", "azimuth", "altitude"]
FIXED = {"t": 1, "azimuth": 1, "altitude": 1, "contact": 0, "pen_down": 0, "pressure": 0}  # line, last value
MEASURED = {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"}
BLOCK = 128
U64 = np.uint64

# The parts, added one at a time: (name, what the variant has).
VARIANTS = [
    ("hsc1: a quadratic per channel, byte planes", dict()),
    ("+ a polynomial chosen per block of 128", dict(chosen=True)),
    ("+ the measured channels as bit lengths and bits", dict(chosen=True, bits=True)),
    ("+ positions from their velocity (fitted a, b)", dict(chosen=True, bits=True, kinematic=True)),
    ("+ what the prediction missed 4 or 8 samples before (hsc2)",
     dict(chosen=True, bits=True, kinematic=True, periodic=True)),
]


def residuals(values, predictions):
    """Zigzagged differences of the 64-bit patterns."""
    with np.errstate(over="ignore"):
        d = values.view(U64) - predictions.view(U64)
    return (d << U64(1)) ^ (U64(0) - (d >> U64(63)))


def bit_lengths(words):
    lengths = np.zeros(len(words), dtype=np.int64)
    rest = words.copy()
    for shift in (32, 16, 8, 4, 2, 1):
        big = rest >= (U64(1) << U64(shift))
        lengths[big] += shift
        rest[big] >>= U64(shift)
    lengths[words > 0] += 1
    return lengths


def polynomial(v, order):
    """The polynomial through the last order+1 values; lower orders at the column's start."""
    p = np.zeros_like(v)
    with np.errstate(over="ignore", invalid="ignore"):
        if len(v) > 1:
            p[1] = v[0]
        if len(v) > 2:
            p[2] = 2.0 * v[1] - v[0]
        if len(v) > 3:
            p[3:] = 3.0 * v[2:-1] - 3.0 * v[1:-2] + v[:-3]
        k = order + 1
        if order != 2 and len(v) > k:
            acc = np.zeros(len(v) - k)
            for j in range(1, k + 1):
                acc = acc + (-1) ** (j + 1) * comb(k, j) * v[k - j:len(v) - j]
            p[k:] = acc
    return p


def plus_miss(v, p, lag, first):
    """The prediction plus what it missed `lag` samples before, from sample `first` + `lag` on
    (`first`: where `p` itself starts: 3 for the quadratic, 1 for the kinematic prediction)."""
    out = p.copy()
    out[lag + first:] = p[lag + first:] + (v[first:-lag] - p[first:-lag])
    return out


def kinematic(p, v, t):
    """p[i-1] + Δt·(a·v[i] + b·v[i-1]), a and b by least squares reweighted towards small misses."""
    dt = np.diff(t)
    x = np.stack([dt * v[1:], dt * v[:-1]], axis=1)
    y = np.diff(p)
    w = np.ones(len(y))
    eps = 1e-9 * np.mean(np.abs(y)) + 1e-300
    a, b = 0.5, 0.5
    for _ in range(3):  # a plain fit, then two reweighted
        sw = np.sqrt(w)
        (a, b), *_ = np.linalg.lstsq(x * sw[:, None], y * sw, rcond=None)
        w = 1.0 / (np.abs(y - x @ np.array([a, b])) + eps)
    out = np.zeros_like(p)
    out[1:] = p[:-1] + dt * (a * v[1:] + b * v[:-1])
    return out


def options(name, columns, variant):
    """The predictions a continuous channel's blocks choose from."""
    v = columns[name]
    if not variant.get("chosen"):
        return [polynomial(v, 2)]
    found = [polynomial(v, order) for order in (0, 1, 2, 3)]
    quadratic = found[2]
    if variant.get("periodic"):
        found += [plus_miss(v, quadratic, 4, 3), plus_miss(v, quadratic, 8, 3)]
    if variant.get("kinematic") and name in ("x", "y", "z"):
        k = kinematic(v, columns["v" + name], columns["t"])
        found.append(k)
        if variant.get("periodic"):
            found.append(plus_miss(v, k, 4, 1) if len(v) > 5 else k)
    return found


def column_residuals(name, columns, variant):
    v = columns[name]
    if name.startswith("cmd_"):
        axis = name[-1]
        return residuals(v, columns["guide_f" + axis] - columns["f" + axis]), 0
    if name in FIXED:
        return residuals(v, polynomial(v, FIXED[name])), 0
    candidates = [residuals(v, p) for p in options(name, columns, variant)]
    lengths = [bit_lengths(r) for r in candidates]
    best = np.zeros(len(v), dtype=U64)
    for start in range(0, len(v), BLOCK):
        block = slice(start, start + BLOCK)
        choice = int(np.argmin([length[block].sum() for length in lengths]))
        best[block] = candidates[choice][block]
    blocks = (len(v) + BLOCK - 1) // BLOCK if variant.get("chosen") else 0
    return best, blocks


def encoded_bytes(columns, names, variant):
    planes, lengths, bit_count, choices = [], [], 0, 0
    for name in names:
        words, blocks = column_residuals(name, columns, variant)
        choices += blocks
        if variant.get("bits") and name in MEASURED:
            length = bit_lengths(words)
            lengths.append((np.diff(np.concatenate([[0], length])) & 255).astype(np.uint8).tobytes())
            bit_count += int(np.maximum(length - 1, 0).sum())
        else:
            planes.append(words)
    shuffled = np.concatenate(planes).view(np.uint8).reshape(-1, 8).T.copy().tobytes()
    parts = [bytes(choices), shuffled, b"".join(lengths)]
    compressor = zstandard.ZstdCompressor(level=1).compressobj()
    size = 0
    for part in parts:
        size += len(compressor.compress(part)) + len(compressor.flush(zstandard.COMPRESSOBJ_FLUSH_BLOCK))
    size += len(compressor.flush())
    return size + (bit_count + 7) // 8  # the packed bits, kept raw


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", required=True, help="a study database (SQLite)")
    parser.add_argument("--every", type=int, default=11, help="measure every Nth trial (default 11)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args()
    if args.every < 1:
        sys.exit(f"--every: expected a whole number >= 1, got {args.every}")
    study = hattr.Study.open(args.db)
    raw, sizes, samples, count = 0, [0] * len(VARIANTS), 0, 0
    for number, trial in enumerate(study.trials()):
        if number % args.every != 0 or trial["status"] != "completed":
            continue
        profile = study.trial_profile(trial["trial_id"])
        present = profile.channel_names
        names = [name for name in STORED if name in present]
        columns = {name: np.ascontiguousarray(profile.channel(name), dtype=np.float64) for name in names}
        raw += len(profile) * len(names) * 8
        samples += len(profile)
        count += 1
        for i, (_, variant) in enumerate(VARIANTS):
            sizes[i] += encoded_bytes(columns, names, variant)
    if count == 0:
        sys.exit(f"{args.db}: no completed trial to measure")
    rows = [{"encoding": name, "bytes": size, "ratio": raw / size} for (name, _), size in zip(VARIANTS, sizes)]
    if args.json:
        print(json.dumps({"db": args.db, "trials": count, "samples": samples, "raw_bytes": raw, "variants": rows}))
        return
    print(f"{count} trials, {samples} samples, {raw} raw bytes")
    for row in rows:
        print(f"{row['ratio']:7.3f}x  {row['bytes']:>11}  {row['encoding']}")


if __name__ == "__main__":
    main()
