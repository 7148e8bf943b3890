#!/usr/bin/env python3
"""Would a lag-sum linear statistic close the family rule's gap on lag-spread linear effects?

An idealised check, not the product: each lag's standardised cross-correlation is taken as
z_tau ~ N(mu_tau, 1), independent over 20 lags (a white dither against a whitened residual). A
first-order-lag effect puts mu_tau = s * w_tau, with w the impulse response of a pole in 0.3-0.8
starting at a lag in 1-15 (as in `crates/mpmwatch/src/power.rs`), scaled to unit energy. Compared
at alpha = 0.01 with critical values from 200 000 null draws:
  max|z| over the lags (what the family's correlation member does), and
  max(max|z|, WH(Q) + offset), Q = sum of z^2, WH its Wilson-Hilferty normal score.
Prints the detection rate at signal sizes s = 1..4 for each offset (None: max|z| alone).

Reference only; the product and its tests never need Python.
    python3 -m venv v && v/bin/pip install numpy
    v/bin/python scripts/lag_sum_power.py
"""

import numpy as np

L, ALPHA, R, CASES, SEED = 20, 0.01, 200_000, 20_000, 5


def wilson_hilferty(q, dof):
    return ((q / dof) ** (1 / 3) - (1 - 2 / (9 * dof))) / np.sqrt(2 / (9 * dof))


def main():
    rng = np.random.default_rng(SEED)
    z0 = rng.standard_normal((R, L))
    null_max = np.abs(z0).max(1)
    null_q = wilson_hilferty((z0**2).sum(1), L)
    taus = np.arange(1, L + 1)
    for offset in [None, -1.0, 0.0, 1.0, 3.0]:
        null = null_max if offset is None else np.maximum(null_max, null_q + offset)
        crit = np.quantile(null, 1 - ALPHA)
        rates = []
        for s in [1.0, 1.5, 2.0, 2.5, 3.0, 4.0]:
            pole = rng.uniform(0.3, 0.8, CASES)
            lag = rng.integers(1, 16, CASES)
            k = taus[None, :] - lag[:, None]
            w = np.where(k >= 0, pole[:, None] ** np.maximum(k, 0), 0.0)
            w /= np.sqrt(1 / (1 - pole**2))[:, None]
            z = s * w + rng.standard_normal((CASES, L))
            m = np.abs(z).max(1)
            stat = m if offset is None else np.maximum(m, wilson_hilferty((z**2).sum(1), L) + offset)
            rates.append((stat >= crit).mean())
        label = "max|z| alone" if offset is None else f"with WH(Q) + {offset:+.1f}"
        print(f"{label:<22} critical {crit:5.2f}  rates " + " ".join(f"{r:.3f}" for r in rates))


if __name__ == "__main__":
    main()
