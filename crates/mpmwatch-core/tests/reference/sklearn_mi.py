"""Reference numbers for crates/mpmwatch-core/tests/it/estimators.rs, from scikit-learn's own KSG estimators.

Run once, by hand, from crates/mpmwatch-core, to (re)generate `tests/reference/sklearn_mi.json`; the Rust tests read the
committed JSON and need no Python:

    pip install scikit-learn numpy
    python3 tests/reference/sklearn_mi.py > tests/reference/sklearn_mi.json

It calls the private functions `_compute_mi_cc` (KSG algorithm 1, max-norm, strict-less-than
marginal counts) and `_compute_mi_cd` (Ross 2014, continuous vs discrete) directly, without the
scaling and noise that `mutual_info_regression` adds. Both clip their result at 0, so every case
uses dependent data whose MI is well above 0. The vectors are written next to the numbers so
the test feeds the Rust estimators the very same doubles (JSON floats round-trip exactly).
"""

import json

import numpy as np
import sklearn
from sklearn.feature_selection._mutual_info import _compute_mi_cc, _compute_mi_cd

rng = np.random.default_rng(20131927)
cases = []

x = rng.standard_normal(500)
y = x + 0.5 * rng.standard_normal(500)
for k in (3, 4):
    cases.append({"name": f"cc_gaussian_k{k}", "kind": "cc", "k": k, "x": x.tolist(), "y": y.tolist(),
                  "mi": float(_compute_mi_cc(x, y, k))})

x = rng.uniform(-2, 2, 400)
y = x ** 2 + 0.3 * rng.standard_normal(400)
cases.append({"name": "cc_parabola_k4", "kind": "cc", "k": 4, "x": x.tolist(), "y": y.tolist(),
              "mi": float(_compute_mi_cc(x, y, 4))})

d = rng.choice([-1.0, 1.0], 500)
c = 0.6 * d + rng.standard_normal(500)
for k in (3, 4):
    cases.append({"name": f"cd_binary_k{k}", "kind": "cd", "k": k, "x": d.tolist(), "y": c.tolist(),
                  "mi": float(_compute_mi_cd(c, d, k))})

d = rng.choice([-1.0, 0.0, 1.0], 300, p=[0.2, 0.5, 0.3])
c = np.abs(d) + 0.5 * rng.standard_normal(300)
cases.append({"name": "cd_three_levels_k4", "kind": "cd", "k": 4, "x": d.tolist(), "y": c.tolist(),
              "mi": float(_compute_mi_cd(c, d, 4))})

print(json.dumps({"sklearn_version": sklearn.__version__, "numpy_version": np.__version__,
                  "seed": 20131927, "cases": cases}))
