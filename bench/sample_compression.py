#!/usr/bin/env python3
"""Candidate encodings of a study's trial samples, measured on a study database's own trials:
the size ratio (raw bytes / encoded bytes, over all trials) and the median time to encode and
to decode one trial, for each candidate, lossless and at a declared per-channel resolution.

    python3 bench/sample_compression.py --db study.sqlite [--trials N] [--json]

The database is one written by hattr's schema 3 (each trial's samples as little-endian doubles,
sample by sample, its stored channels in file-column order), before the migration to schema 4
compressed them. Every candidate's decoding is
checked against the original (bit for bit when lossless, the quantized values otherwise)
before any figure is printed. Needs Debian's python3-numpy, python3-zstandard, python3-blosc."""

import argparse
import json
import sqlite3
import statistics
import sys
import time

import blosc
import numpy as np
import zstandard

# The stored channels in file-column order (src/core/channel.cpp), and hattr's default
# declared resolution of each (SI units): what quantized candidates round to.
CHANNELS = ["t", "x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz", "cmd_fx", "cmd_fy", "cmd_fz",
            "guide_fx", "guide_fy", "guide_fz", "contact", "pen_down", "pressure", "azimuth", "altitude"]
RESOLUTION = {"t": 1e-6, "x": 1e-6, "y": 1e-6, "z": 1e-6, "vx": 1e-5, "vy": 1e-5, "vz": 1e-5,
              "fx": 1e-3, "fy": 1e-3, "fz": 1e-3, "cmd_fx": 1e-3, "cmd_fy": 1e-3, "cmd_fz": 1e-3,
              "guide_fx": 1e-3, "guide_fy": 1e-3, "guide_fz": 1e-3, "contact": 1.0, "pen_down": 1.0,
              "pressure": 1.0, "azimuth": 1e-4, "altitude": 1e-4}


def stored_channels(raw_pressure, raw_tilt):
    return [c for c in CHANNELS
            if (c != "pressure" or raw_pressure) and (c not in ("azimuth", "altitude") or raw_tilt)]


def read_trials(db, limit, every=1):
    """Each trial as (channel names, samples × channels float64 array)."""
    connection = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    columns = [row[1] for row in connection.execute("PRAGMA table_info(samples)")]
    if "encoding" in columns:
        sys.exit(f"{db}: its samples are already compressed (schema 4); measure a schema-3 study")
    rows = connection.execute("SELECT raw_pressure, raw_tilt, sample_count, data FROM samples ORDER BY trial")
    trials = []
    for number, (raw_pressure, raw_tilt, count, data) in enumerate(rows):
        if number % every != 0:
            continue
        if len(trials) == limit:
            break
        names = stored_channels(raw_pressure, raw_tilt)
        trials.append((names, np.frombuffer(data, dtype="<f8").reshape(count, len(names))))
    return trials


def shuffle(words):
    """Byte shuffle of 8-byte words: all first bytes, then all second bytes, ..."""
    return words.view(np.uint8).reshape(-1, 8).T.copy().tobytes()


def unshuffle(data, count):
    return np.frombuffer(data, dtype=np.uint8).reshape(8, count).T.copy().view("<u8").ravel()


def xor_delta(bits):
    """Each channel's bit patterns XOR their predecessor's (the first kept): exact, reversible."""
    out = bits.copy()
    out[1:] ^= bits[:-1]
    return out


def undo_xor_delta(bits):
    return np.bitwise_xor.accumulate(bits, axis=0)


def zigzag_delta(ints):
    """Differences of each channel's integers, zigzagged so that small ± values are small."""
    d = np.diff(ints, axis=0, prepend=np.zeros((1, ints.shape[1]), dtype=np.int64))
    return ((d << 1) ^ (d >> 63)).astype(np.uint64)


def undo_zigzag_delta(z):
    d = (z >> np.uint64(1)).astype(np.int64) ^ -(z & np.uint64(1)).astype(np.int64)
    return np.cumsum(d, axis=0)


def candidates(level):
    """name -> (encode(columns[, steps or names]) -> bytes, decode(bytes, shape[, ...]) -> columns,
    what else they take: True for the steps (quantized), "names" for the channel names)."""
    cz = zstandard.ZstdCompressor(level=level)
    dz = zstandard.ZstdDecompressor()

    def rows_zstd():
        return (lambda x: cz.compress(np.ascontiguousarray(x).tobytes()),
                lambda b, shape: np.frombuffer(dz.decompress(b), dtype="<f8").reshape(shape), False)

    def columns_zstd():
        return (lambda x: cz.compress(np.asfortranarray(x).tobytes(order="F")),
                lambda b, shape: np.frombuffer(dz.decompress(b), dtype="<f8").reshape(shape, order="F"), False)

    def columns_shuffle_zstd():
        return (lambda x: cz.compress(shuffle(np.asfortranarray(x).ravel(order="F").view("<u8"))),
                lambda b, shape: unshuffle(dz.decompress(b), shape[0] * shape[1]).view("<f8").reshape(shape, order="F"),
                False)

    def columns_xor_shuffle_zstd():
        def encode(x):
            bits = np.ascontiguousarray(x).view("<u8")
            return cz.compress(shuffle(xor_delta(bits).ravel(order="F")))

        def decode(b, shape):
            bits = unshuffle(dz.decompress(b), shape[0] * shape[1]).reshape(shape, order="F")
            return np.ascontiguousarray(undo_xor_delta(bits)).view("<f8")
        return encode, decode, False

    def columns_prediction_shuffle_zstd():
        # Each value XOR its linear prediction 2 x[i-1] - x[i-2] (in doubles, which the decoder
        # computes again from the values it has decoded): smooth signals leave mostly zero bits.
        def encode(x):
            pred = np.zeros_like(x)
            pred[1] = x[0] if len(x) > 1 else 0.0
            pred[2:] = 2.0 * x[1:-1] - x[:-2]
            residual = np.ascontiguousarray(x).view("<u8") ^ pred.view("<u8")
            return cz.compress(shuffle(residual.ravel(order="F")))

        def decode(b, shape):
            residual = unshuffle(dz.decompress(b), shape[0] * shape[1]).reshape(shape, order="F")
            x = np.zeros(shape)
            bits = x.view("<u8")
            for i in range(shape[0]):
                pred = np.zeros(shape[1]) if i == 0 else x[0] if i == 1 else 2.0 * x[i - 1] - x[i - 2]
                bits[i] = residual[i] ^ pred.view("<u8")
            return x
        return encode, decode, False

    def hattr_encoding():
        # io/sample_codec.cpp: per channel a quadratic through the last three values (a line
        # for time and tilt, the last value for flags and pressure), the commanded force as
        # guidance force minus the user's force; the zigzagged integer difference of the bit
        # patterns, byte planes, zstd.
        def predictors(names):
            return [0 if n in ("contact", "pen_down", "pressure") else 1 if n in ("t", "azimuth", "altitude")
                    else 3 if n.startswith("cmd_") else 2 for n in names]

        def predict(x, i, order, names, c):
            if order == 3:
                a = names[c][len("cmd_"):]
                return x[i, names.index("guide_" + a)] - x[i, names.index(a)]
            if i == 0:
                return 0.0
            if order == 0 or i == 1:
                return x[i - 1, c]
            if order == 1 or i == 2:
                return 2.0 * x[i - 1, c] - x[i - 2, c]
            return 3.0 * x[i - 1, c] - 3.0 * x[i - 2, c] + x[i - 3, c]

        def columns_of(x, names):
            order = predictors(names)
            pred = np.zeros_like(x)
            for c, o in enumerate(order):
                col = x[:, c]
                if o == 3:
                    a = names[c][len("cmd_"):]
                    pred[:, c] = x[:, names.index("guide_" + a)] - x[:, names.index(a)]
                    continue
                if len(col) > 1:
                    pred[1, c] = col[0]
                if o == 0:
                    pred[1:, c] = col[:-1]
                elif len(col) > 2:
                    pred[2:, c] = 2.0 * col[1:-1] - col[:-2]
                    if o == 2 and len(col) > 3:
                        pred[3:, c] = 3.0 * col[2:-1] - 3.0 * col[1:-2] + col[:-3]
            d = np.ascontiguousarray(x).view("<i8") - pred.view("<i8")
            return ((d << 1) ^ (d >> 63)).view("<u8")

        def encode(x, names):
            return cz.compress(shuffle(np.ascontiguousarray(columns_of(x, names).ravel(order="F"))))

        def decode(b, shape, names):
            z = unshuffle(dz.decompress(b), shape[0] * shape[1]).reshape(shape, order="F")
            d = (z >> np.uint64(1)).view("<i8") ^ -(z & np.uint64(1)).view("<i8")
            x = np.zeros(shape)
            order = predictors(names)
            with np.errstate(over="ignore"):  # the integer sums wrap, as in C++
                for c in sorted(range(shape[1]), key=lambda c: order[c] == 3):
                    for i in range(shape[0]):
                        p = np.array([predict(x, i, order[c], names, c)]).view("<i8")[0]
                        x[i, c] = np.array([d[i, c] + p]).view("<f8")[0]
            return x
        return encode, decode, "names"

    def blosc_columns(shuffle_kind):
        return (lambda x: blosc.compress(np.asfortranarray(x).tobytes(order="F"), typesize=8, clevel=min(level, 9),
                                         shuffle=shuffle_kind, cname="zstd"),
                lambda b, shape: np.frombuffer(blosc.decompress(b), dtype="<f8").reshape(shape, order="F"), False)

    def quantized_shuffle_zstd():
        def encode(x, steps):
            ints = np.rint(x / steps).astype(np.int64)
            return cz.compress(shuffle(zigzag_delta(ints).ravel(order="F")))

        def decode(b, shape, steps):
            z = unshuffle(dz.decompress(b), shape[0] * shape[1]).reshape(shape, order="F")
            return undo_zigzag_delta(z) * steps
        return encode, decode, True

    return {
        "rows + zstd": rows_zstd(),
        "columns + zstd": columns_zstd(),
        "columns + byte shuffle + zstd": columns_shuffle_zstd(),
        "columns + xor delta + byte shuffle + zstd": columns_xor_shuffle_zstd(),
        "columns + xor linear prediction + byte shuffle + zstd": columns_prediction_shuffle_zstd(),
        "hattr: prediction + zigzag + byte shuffle + zstd": hattr_encoding(),
        "blosc (zstd, byte shuffle), columns": blosc_columns(blosc.SHUFFLE),
        "blosc (zstd, bit shuffle), columns": blosc_columns(blosc.BITSHUFFLE),
        "quantized: delta + zigzag + byte shuffle + zstd": quantized_shuffle_zstd(),
    }


def measure(trials, name, codec):
    encode, decode, takes = codec
    quantized = takes is True
    raw = packed = 0
    encode_s, decode_s = [], []
    for names, x in trials:
        steps = np.array([RESOLUTION[c] for c in names])
        extra = (names,) if takes == "names" else (steps,) if quantized else ()
        start = time.perf_counter()
        blob = encode(x, *extra)
        encode_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        back = decode(blob, x.shape, *extra)
        decode_s.append(time.perf_counter() - start)
        # A quantized channel holds whole multiples of its step (k * step, so never -0.0).
        expected = np.rint(x / steps).astype(np.int64) * steps if quantized else x
        if not np.array_equal(np.ascontiguousarray(back).view("<u8"), np.ascontiguousarray(expected).view("<u8")):
            sys.exit(f"{name}: the decoded samples differ from the {'quantized' if quantized else 'original'} ones")
        raw += x.nbytes
        packed += len(blob)
    return {"candidate": name, "ratio": raw / packed, "encode_ms": 1e3 * statistics.median(encode_s),
            "decode_ms": 1e3 * statistics.median(decode_s)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--db", required=True, help="a study database written by hattr")
    parser.add_argument("--trials", type=int, default=60, help="trials to measure (default 60)")
    parser.add_argument("--every", type=int, default=1, help="take every k-th stored trial (default 1: each)")
    parser.add_argument("--levels", default="1,3,9", help="zstd / blosc levels, comma-separated (default 1,3,9)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    arguments = parser.parse_args()
    trials = read_trials(arguments.db, arguments.trials, arguments.every)
    if not trials:
        sys.exit(f"{arguments.db}: no trial has samples")
    results = []
    for level in (int(v) for v in arguments.levels.split(",")):
        for name, codec in candidates(level).items():
            results.append({"level": level, **measure(trials, name, codec)})
    samples = sum(x.shape[0] for _, x in trials)
    if arguments.json:
        print(json.dumps({"db": arguments.db, "trials": len(trials), "every": arguments.every, "samples": samples,
                      "results": results}))
        return
    print(f"{len(trials)} trials, {samples} samples, {trials[0][1].shape[1]} channels")
    print(f"{'candidate':<50} {'level':>5} {'ratio':>7} {'encode ms':>10} {'decode ms':>10}")
    for r in results:
        print(f"{r['candidate']:<50} {r['level']:>5} {r['ratio']:>7.2f} {r['encode_ms']:>10.2f} {r['decode_ms']:>10.2f}")


if __name__ == "__main__":
    main()
