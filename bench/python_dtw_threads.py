#!/usr/bin/env python3
"""DTW batches from Python threads: the same pairs on 1 thread and on N threads (the GIL is
released inside hattr.dtw_batch), the speed-up as a ratio measured in the same run.

    PYTHONPATH=build/release/python python3 bench/python_dtw_threads.py --json

Prints a table, or with --json one object: pairs, length, threads, best-of-repeats seconds for
1 and N threads, the speed-up, and the DTW instruction set. The costs of both runs are compared
(they must be equal) before any figure is printed."""

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


def run(pool, a, b, threads):
    """All pairs as `threads` equal batches on the pool's Python threads; the costs in pair order."""
    chunks = np.array_split(np.arange(len(a)), threads)
    parts = pool.map(lambda idx: hattr.dtw_batch([a[i] for i in idx], [b[i] for i in idx]), chunks)
    return np.concatenate(list(parts))


def best_times(a, b, threads, repeats):
    """Best wall time of 1 thread and of `threads`, the two measured in turn so that both see the
    same machine; and the costs of each."""
    best = {1: float("inf"), threads: float("inf")}
    costs = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=threads) as pool:
        for _ in range(repeats):
            for n in best:
                start = time.perf_counter()
                costs[n] = run(pool, a, b, n)
                best[n] = min(best[n], time.perf_counter() - start)
    return best[1], costs[1], best[threads], costs[threads]


def main():
    arguments = parse_arguments()
    rng = np.random.default_rng(1)
    a = [rng.normal(size=arguments.length) for _ in range(arguments.pairs)]
    b = [rng.normal(size=arguments.length) for _ in range(arguments.pairs)]
    one_s, one_costs, many_s, many_costs = best_times(a, b, arguments.threads, arguments.repeats)
    if not np.array_equal(one_costs, many_costs):
        sys.exit("python_dtw_threads: the threaded costs differ from the single-thread ones")
    result = {"pairs": arguments.pairs, "length": arguments.length, "threads": arguments.threads,
              "one_thread_s": one_s, "threads_s": many_s, "speedup": one_s / many_s,
              "cells_per_s_one_thread": arguments.pairs * arguments.length**2 / one_s,
              "simd": hattr.dtw_simd_target()}
    if arguments.json:
        print(json.dumps(result, indent=2))
        return
    print(f"{arguments.pairs} pairs of {arguments.length} points, best of {arguments.repeats} ({result['simd']})")
    print(f"  1 thread:  {one_s * 1e3:8.1f} ms")
    print(f"  {arguments.threads} threads: {many_s * 1e3:8.1f} ms   speed-up {result['speedup']:.2f}x")


if __name__ == "__main__":
    main()
