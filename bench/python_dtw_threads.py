#!/usr/bin/env python3
"""DTW batches on threads: the same pairs as one batch on 1 thread, as one batch on N threads
(hattr.dtw_batch(..., threads=N)), and as N batches on N Python threads (the GIL is released
inside hattr.dtw_batch); the speed-ups as ratios against the first, measured in the same run.

    PYTHONPATH=build/release/python python3 bench/python_dtw_threads.py --json

Prints a table, or with --json one object: pairs, length, threads, the best-of-repeats seconds
of each way, the speed-ups, and the DTW instruction set. The costs of the three ways are
compared (they must be equal) before any figure is printed."""

import argparse
import concurrent.futures
import json
import sys
import time

import numpy as np

import hattr


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=128, help="pairs of series (default 128)")
    parser.add_argument("--length", type=int, default=1000, help="points per series (default 1000)")
    parser.add_argument("--threads", type=int, default=4, help="Python threads to compare with one (default 4)")
    parser.add_argument("--repeats", type=int, default=10, help="runs of each, in turn; the best counts (default 10)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    arguments = parser.parse_args()
    if arguments.pairs < arguments.threads or min(arguments.length, arguments.threads, arguments.repeats) < 1:
        parser.error("need pairs >= threads >= 1, length >= 1 and repeats >= 1")
    return arguments


def python_threads(pool, a, b, threads):
    """All pairs as `threads` equal batches on the pool's Python threads; the costs in pair order."""
    chunks = np.array_split(np.arange(len(a)), threads)
    parts = pool.map(lambda idx: hattr.dtw_batch([a[i] for i in idx], [b[i] for i in idx]), chunks)
    return np.concatenate(list(parts))


def best_times(a, b, threads, repeats):
    """Best wall time and costs of each way, the ways measured in turn so that all see the same machine."""
    with concurrent.futures.ThreadPoolExecutor(max_workers=threads) as pool:
        ways = {"one_thread": lambda: hattr.dtw_batch(a, b),
                "batch_threads": lambda: hattr.dtw_batch(a, b, threads=threads),
                "python_threads": lambda: python_threads(pool, a, b, threads)}
        best = {name: float("inf") for name in ways}
        costs = {}
        for _ in range(repeats):
            for name, way in ways.items():
                start = time.perf_counter()
                costs[name] = way()
                best[name] = min(best[name], time.perf_counter() - start)
    return best, costs


def main():
    arguments = parse_arguments()
    rng = np.random.default_rng(1)
    a = [rng.normal(size=arguments.length) for _ in range(arguments.pairs)]
    b = [rng.normal(size=arguments.length) for _ in range(arguments.pairs)]
    best, costs = best_times(a, b, arguments.threads, arguments.repeats)
    if not all(np.array_equal(costs["one_thread"], c) for c in costs.values()):
        sys.exit("python_dtw_threads: the threaded costs differ from the single-thread ones")
    one_s = best["one_thread"]
    result = {"pairs": arguments.pairs, "length": arguments.length, "threads": arguments.threads,
              "one_thread_s": one_s, "batch_threads_s": best["batch_threads"],
              "python_threads_s": best["python_threads"], "speedup_batch_threads": one_s / best["batch_threads"],
              "speedup_python_threads": one_s / best["python_threads"],
              "cells_per_s_one_thread": arguments.pairs * arguments.length**2 / one_s,
              "simd": hattr.dtw_simd_target()}
    if arguments.json:
        print(json.dumps(result, indent=2))
        return
    n = arguments.threads
    print(f"{arguments.pairs} pairs of {arguments.length} points, best of {arguments.repeats} ({result['simd']})")
    print(f"  1 thread:                   {one_s * 1e3:8.1f} ms")
    print(f"  dtw_batch(threads={n}):       {best['batch_threads'] * 1e3:8.1f} ms   "
          f"speed-up {result['speedup_batch_threads']:.2f}x")
    print(f"  {n} Python threads:           {best['python_threads'] * 1e3:8.1f} ms   "
          f"speed-up {result['speedup_python_threads']:.2f}x")


if __name__ == "__main__":
    main()
