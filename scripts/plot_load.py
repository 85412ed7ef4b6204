#!/usr/bin/env python3
"""The load benchmark's CSV (scripts/bench_load) as four panels over time:
node RSS, CPU, the samples in the current session, and the age of detections
when the node handled them."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path, png_path):
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t_s"]) / 60.0 for r in rows]
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    axes[0].plot(t, [float(r["node_rss_mb"]) for r in rows])
    axes[0].set_ylabel("node RSS [MB]")
    axes[0].set_ylim(bottom=0)
    axes[1].plot(t, [float(r["node_cpu_percent"]) for r in rows], label="calibration node")
    axes[1].plot(t, [float(r["driver_cpu_percent"]) for r in rows], label="load driver")
    axes[1].set_ylabel("CPU [% of a core]")
    axes[1].legend()
    axes[2].plot(t, [int(r["samples"]) for r in rows])
    axes[2].set_ylabel("samples in the session")
    axes[2].set_ylim(bottom=0)
    for key, label in (("age_median_ms", "median"), ("age_p99_ms", "p99"), ("age_max_ms", "max")):
        axes[3].plot(t, [float(r[key]) for r in rows], label=label)
    axes[3].set_ylabel("detection age [ms]\n(last 300 detections)")
    axes[3].set_yscale("log")
    axes[3].legend()
    axes[3].set_xlabel("time [min]")
    fig.suptitle("calibration node under TF 1 kHz + detections 30 Hz")
    fig.tight_layout()
    fig.savefig(png_path, dpi=90)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
