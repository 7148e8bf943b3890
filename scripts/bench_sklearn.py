#!/usr/bin/env python3
"""Side-by-side timing of one MI estimate: scikit-learn against `mpmwatch bench`, in one run.

Times scikit-learn's own estimators, `_compute_mi_cd` (Ross 2014, discrete x: the binary-dither
case) and `_compute_mi_cc` (KSG algorithm 1), at N samples and k = 4, on data of the kind
`mpmwatch bench` draws (a +-1 dither, an AR(1) residual with a = 0.7 plus 0.3 times the dither
one sample earlier; a continuous AR(1) with a = 0.5), then runs `mpmwatch bench --json` on the
same machine straight after, alternating the two for a few rounds, and prints each round's
medians and ratios and the median ratio. Neither side's data is
the other's (different generators), only its kind and size; the estimators' cost depends on
those, not on the draws.

Reference only; the product and its tests never need Python.
    python3 -m venv v && v/bin/pip install scikit-learn numpy
    cargo build --release
    v/bin/python scripts/bench_sklearn.py --bin target/release/mpmwatch --n 2048
"""

import argparse
import json
import statistics
import subprocess
import time

import numpy as np
import sklearn
from sklearn.feature_selection._mutual_info import _compute_mi_cc, _compute_mi_cd


def ar1(rng, n, a):
    e = rng.standard_normal(n)
    v = np.empty(n)
    v[0] = e[0]
    for t in range(1, n):
        v[t] = a * v[t - 1] + e[t]
    return v


def median_ms(reps, f):
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        f()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/mpmwatch")
    ap.add_argument("--n", type=int, default=2048)
    ap.add_argument("--reps", type=int, default=50)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=5,
                    help="alternate the two sides this many times and report the median ratio (a shared "
                         "machine's speed drifts between runs; each round times both sides within seconds)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    n, k = args.n, 4
    d = rng.choice([-1.0, 1.0], n)
    r = ar1(rng, n, 0.7)
    r[1:] += 0.3 * d[:-1]
    c = ar1(rng, n, 0.5)
    rows = []
    for _ in range(args.rounds):
        sk_binary = median_ms(args.reps, lambda: _compute_mi_cd(r, d, k))
        sk_cont = median_ms(args.reps, lambda: _compute_mi_cc(c, r, k))
        out = subprocess.run([args.bin, "bench", "--n", str(n), "--reps", str(args.reps), "--seed",
                              str(args.seed), "--json"], check=True, capture_output=True, text=True).stdout
        ours = json.loads(out)
        rows.append((sk_binary, ours["ksg_binary_ms"], sk_cont, ours["ksg_continuous_ms"],
                     ours["ksg_binary_per_lag_ms"]))
    print(f"N = {n}, k = {k}, {args.reps} repetitions, medians; scikit-learn {sklearn.__version__}, "
          f"numpy {np.__version__}; {args.rounds} rounds")
    print(f"{'round':<7}{'binary: sklearn':>16}{'mpmwatch':>10}{'ratio':>8}{'per lag':>10}{'ratio':>8}"
          f"{'continuous: sklearn':>21}{'mpmwatch':>10}{'ratio':>8}")
    for i, (sb, ub, sc, uc, ul) in enumerate(rows, 1):
        print(f"{i:<7}{sb:>13.3f} ms{ub:>7.3f} ms{sb / ub:>7.1f}x{ul:>7.3f} ms{sb / ul:>7.1f}x"
              f"{sc:>18.3f} ms{uc:>7.3f} ms{sc / uc:>7.1f}x")
    print(f"median ratio: binary dither (Ross) {statistics.median(r[0] / r[1] for r in rows):.1f}x one-off, "
          f"{statistics.median(r[0] / r[4] for r in rows):.1f}x per lag of a profile; "
          f"continuous (KSG1) {statistics.median(r[2] / r[3] for r in rows):.1f}x")


if __name__ == "__main__":
    main()
