#!/usr/bin/python3
"""Memory bandwidth of this machine, one thread, for the physical limit of the MD loop
(docs/benchmarks.md, "Memory traffic of the neutral step"): the STREAM "add" kernel a = b + c
(numpy, float64: 16 bytes read and 8 written per element) over working sets from the
second-level cache to main memory. Each size reports the best of REPEATS passes, in GB/s of
bytes moved (reads plus writes; write-allocate traffic not counted, as STREAM does).

usage: /usr/bin/python3 scripts/bandwidth.py [--repeats R] [--sizes MB,MB,...]
"""
import argparse
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--sizes", default="1,8,16,24,32,48,128,512,1536",
                    help="working sets in MB (three arrays together)")
    a = ap.parse_args()
    print("| working set | GB/s (best of %d) |" % a.repeats)
    print("|---|---|")
    for mb in (float(s) for s in a.sizes.split(",")):
        n = max(1, int(mb * 1e6 / 24))
        b = np.random.default_rng(1).random(n)
        c = np.random.default_rng(2).random(n)
        out = np.empty(n)
        np.add(b, c, out=out)  # touch every page first
        reps = a.repeats if mb < 256 else max(3, a.repeats // 4)
        best = float("inf")
        for _ in range(reps):
            t0 = time.perf_counter()
            np.add(b, c, out=out)
            best = min(best, time.perf_counter() - t0)
        print("| %g MB | %.1f |" % (mb, 24 * n / best / 1e9))


if __name__ == "__main__":
    main()
