"""Plots for `handeye validate` (matplotlib, from Debian's python3-matplotlib).

Reads DIR/validation.csv and DIR/covariances.csv and writes
  DIR/fig3_epsilon.png         epsilon (eq. 63) against lambda, with the Monte-Carlo sampling floor
  DIR/fig2_<protocol>.png      1-sigma ellipses of the predicted and Monte-Carlo covariances,
                               projected on axis pairs (the paper's Fig. 2), at the lambda nearest 1e-5
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/validation.csv")))
covariances = {}
for line in csv.reader(open(f"{out}/covariances.csv")):
    covariances[(line[0], float(line[1]), line[2])] = np.array([float(v) for v in line[3:]]).reshape(6, 6)

protocols = list(dict.fromkeys(r["protocol"] for r in rows))

# Fig. 3: epsilon against lambda.
fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for ax, block, title in ((axes[0], "R", "rotation"), (axes[1], "t", "translation")):
    for protocol in protocols:
        mine = [r for r in rows if r["protocol"] == protocol]
        lam = [float(r["lambda"]) for r in mine]
        eps = [float(r[f"eps_{block}"]) for r in mine]
        floor = [float(r[f"floor_{block}"]) for r in mine]
        (line,) = ax.plot(lam, eps, "o-", label=f"{protocol}")
        ax.fill_between(lam, 0, [1.2 * f for f in floor], color=line.get_color(), alpha=0.12)
        ax.plot(lam, floor, ":", color=line.get_color())
    ax.set_xscale("log")
    ax.set_xlabel("lambda")
    ax.set_title(f"{title}: epsilon (eq. 63); dotted: sampling floor, band: 1.2 x floor")
    ax.grid(True, alpha=0.3)
axes[0].set_ylabel("epsilon")
axes[0].legend()
fig.tight_layout()
fig.savefig(f"{out}/fig3_epsilon.png", dpi=110)

# Fig. 2: 1-sigma ellipses on axis pairs.
names = ["t_x [mm]", "t_y [mm]", "t_z [mm]", "xi_x [deg]", "xi_y [deg]", "xi_z [deg]"]
scale = np.array([1e3, 1e3, 1e3, 180 / math.pi, 180 / math.pi, 180 / math.pi])
pairs = [(3, 4), (3, 5), (4, 5), (0, 1), (0, 2), (1, 2)]
theta = np.linspace(0, 2 * math.pi, 200)
circle = np.vstack([np.cos(theta), np.sin(theta)])
for protocol in protocols:
    lambdas = sorted({k[1] for k in covariances if k[0] == protocol})
    lam = min(lambdas, key=lambda l: abs(math.log10(l) + 5))
    fig, axes = plt.subplots(2, 3, figsize=(12, 7))
    for ax, (i, j) in zip(axes.flat, pairs):
        for kind, style in (("predicted", "-"), ("monte_carlo", "--")):
            C = covariances[(protocol, lam, kind)][np.ix_([i, j], [i, j])] * np.outer(scale[[i, j]], scale[[i, j]])
            values, vectors = np.linalg.eigh(C)
            ellipse = vectors @ np.diag(np.sqrt(np.maximum(values, 0))) @ circle
            ax.plot(ellipse[0], ellipse[1], style, label="predicted" if kind == "predicted" else "Monte-Carlo")
        ax.set_xlabel(names[i])
        ax.set_ylabel(names[j])
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend()
    fig.suptitle(f"{protocol}, lambda = {lam:g}: 1-sigma ellipses, predicted vs Monte-Carlo")
    fig.tight_layout()
    fig.savefig(f"{out}/fig2_{protocol}.png", dpi=110)
